"""The Dask cluster that studies and the server start: every endpoint on loopback, mutual TLS with
credentials made for it alone, no dashboard; an existing cluster off this machine only over TLS
with credentials."""

import argparse
import gc

import psutil
import pytest
from distributed import Client, Security

from train.study.cluster import add_cluster_args, make_client, remote_security


def _args(*argv: str) -> argparse.Namespace:
  p = argparse.ArgumentParser()
  add_cluster_args(p)
  return p.parse_args(list(argv))


def _listening(procs) -> list[str]:
  return [c.laddr.ip for proc in procs for c in proc.net_connections(kind="inet") if c.status == "LISTEN"]


def _connects(address: str, security) -> bool:
  """Whether a client with these credentials (None: none) can run code in the scheduler."""
  try:
    with Client(address, security=security, timeout=5) as other:
      return other.run_on_scheduler(lambda: 7) == 7
  except Exception:  # noqa: BLE001  (any refusal: TLS handshake, certificate, time-out)
    return False
  finally:
    # a Client refused in its constructor is left half-built in a reference cycle; collected later
    # inside the next Client's start-up, its __del__ -> close() waits for the lock that start-up
    # holds (a hang seen in CI): collect it here, while no lock is held
    gc.collect()


def test_the_local_cluster_listens_on_loopback_only_and_refuses_clients_without_its_credentials():
  before = set(_listening([psutil.Process()]))
  client, kinds = make_client(_args("--cpu-slots", "1"))
  with client:
    assert kinds == ("cpu",) and client.scheduler.address.startswith("tls://127.0.0.1:")
    assert client.submit(lambda: 41 + 1, resources={"cpu": 1}).result() == 42  # its own client works
    procs = [psutil.Process(), *psutil.Process().children(recursive=True)]
    opened = [ip for ip in _listening(procs) if ip not in before] or _listening(procs)
    assert opened and set(opened) == {"127.0.0.1"}  # scheduler, nanny, worker, their HTTP ports
    assert not _connects(client.scheduler.address, None)  # no credentials
    assert not _connects(client.scheduler.address, Security.temporary())  # someone else's credentials
    assert not _connects(client.scheduler.address.replace("tls://", "tcp://"), None)


@pytest.mark.parametrize("address, files, error", [
    ("tcp://10.1.2.3:8786", (None, None, None), "needs tls://"),
    ("tls://example.org:8786", (None, None, None), "needs tls://"),
    ("tcp://10.1.2.3:8786", ("ca", "cert", "key"), "need a tls:// address"),
    ("tls://10.1.2.3:8786", ("ca", None, None), "go together"),
])
def test_an_existing_cluster_off_this_machine_needs_tls_and_credentials(address, files, error):
  with pytest.raises(ValueError, match=error):
    remote_security(address, *files)


def test_an_existing_cluster_on_loopback_is_trusted_as_given():
  assert remote_security("tcp://127.0.0.1:8786", None, None, None) is None
  assert remote_security("localhost:8786", None, None, None) is None

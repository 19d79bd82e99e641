"""The server in a thread of this process, on a free local port: for tests, benchmarks and
screenshots, which drive it with a browser."""

from __future__ import annotations

import socket
import threading
import time


def serve_in_thread(app, log_level: str = "warning") -> tuple[str, object]:
  """Serves a FastAPI app on a free 127.0.0.1 port (log_level "info": with an access log);
  returns (base URL, stop())."""
  import uvicorn  # noqa: PLC0415
  with socket.socket() as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
  server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level=log_level))
  thread = threading.Thread(target=server.run, daemon=True)
  thread.start()
  while not server.started:
    time.sleep(0.05)

  def stop() -> None:
    server.should_exit = True
    thread.join(10)

  return f"http://127.0.0.1:{port}", stop

"""Ctrl-C and SIGTERM during training: the first asks the loop to stop after the current update
(it then checkpoints, exports and exits 130 / 143). Only a second Ctrl-C (SIGINT) from the user, at
least QUIT_AFTER_S after the first request, exits at once; further SIGTERMs never do. Schedulers
(`timeout`, SLURM, `docker stop`, a process-group kill) send SIGTERM to the process and to its
group, so one stop can arrive twice within microseconds: it must still save.

Signals are read by a watcher thread through `signal.set_wakeup_fd`, so they are seen at once
even while the main thread is inside a long XLA compilation or a device computation (Python
runs its own handlers only between bytecodes of the main thread).
"""

from __future__ import annotations

import os
import signal
import socket
import sys
import threading
import time

QUIT_AFTER_S = 1.0  # a second Ctrl-C sooner than this after the first request is the same keypress's echo
EXIT_CODE = {signal.SIGINT: 130, signal.SIGTERM: 143}  # 128 + signal number, as shells report


class StopRequest:
  """Installed for the duration of a `with` block; `requested` is the first signal, if any."""

  def __init__(self, stream=None):
    self.requested: int | None = None
    self.requested_at = 0.0  # time.monotonic() of the first request
    self.stream = stream or sys.stderr  # as it is now, not at import (a caller may have redirected it)
    self._old = {}
    self._old_fd = -1
    self._reader = self._writer = None

  def __enter__(self) -> "StopRequest":
    if threading.current_thread() is not threading.main_thread():
      return self  # signals cannot be caught off the main thread (e.g. a test harness); nothing to do
    self._reader, self._writer = socket.socketpair()
    self._writer.setblocking(False)
    for sig in EXIT_CODE:
      self._old[sig] = signal.signal(sig, lambda *_: None)  # the watcher acts; Python must not raise
    self._old_fd = signal.set_wakeup_fd(self._writer.fileno(), warn_on_full_buffer=False)
    threading.Thread(target=self._watch, name="stop-request", daemon=True).start()
    return self

  def _watch(self) -> None:
    while True:
      try:
        data = self._reader.recv(16)
      except OSError:
        return
      if not data:
        return
      for signum in data:
        self._on_signal(signum)

  def _on_signal(self, signum: int) -> None:
    if self.requested is None:
      print(f"{signal.Signals(signum).name}: stopping after this update to save a checkpoint and the policy "
            "(press Ctrl-C again to quit at once)", file=self.stream, flush=True)
      self.requested_at = time.monotonic()
      self.requested = signum  # after the message: the loop's own output cannot cut into it
    elif signum == signal.SIGINT and time.monotonic() - self.requested_at >= QUIT_AFTER_S:
      print("second interrupt: exiting at once (the last checkpoint is kept)", file=self.stream, flush=True)
      os._exit(EXIT_CODE.get(self.requested, 130))
    else:
      print(f"{signal.Signals(signum).name} again: still stopping, saving first (Ctrl-C again in a second "
            "quits at once)", file=self.stream, flush=True)

  @property
  def exit_code(self) -> int:
    return EXIT_CODE.get(self.requested, 130)

  def __exit__(self, *exc) -> None:
    if self._writer is None:
      return
    signal.set_wakeup_fd(self._old_fd)
    for sig, handler in self._old.items():
      signal.signal(sig, handler)
    self._writer.close()
    self._reader.close()

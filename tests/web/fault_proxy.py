"""A TCP proxy in front of a study server that fails as the real internet does (the jsPsych
plugin's browser tests, #40): ``down()`` — every connection, open or new, is cut at once (a
server restart, a dropped link); ``silent()`` — connections are taken and never answered (a
frozen proxy or server); ``up()`` — bytes flow again. ``outage(seconds)`` is down, then up.
A listener that never answers at all is :class:`SilentListener`.
"""

from __future__ import annotations

import contextlib
import socket
import threading
from types import TracebackType


def _listener() -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind(("127.0.0.1", 0))
    sock.listen(64)
    return sock


class FaultProxy:
    """Forwards 127.0.0.1:``port`` to ``target_port``, failing on demand."""

    def __init__(self, target_port: int) -> None:
        self.target_port = target_port
        self.mode = "up"
        self.sock = _listener()
        self.port = self.sock.getsockname()[1]
        self.lock = threading.Lock()
        self.open: set[socket.socket] = set()
        self.held: list[socket.socket] = []  # taken while silent, never answered
        threading.Thread(target=self._accept, daemon=True).start()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def down(self) -> None:
        with self.lock:
            self.mode = "down"
            for s in self.open:
                with contextlib.suppress(OSError):
                    s.shutdown(socket.SHUT_RDWR)
            self.open.clear()

    def silent(self) -> None:
        self.down()
        self.mode = "silent"

    def up(self) -> None:
        self.mode = "up"

    def outage(self, seconds: float) -> threading.Timer:
        """Down now, up after ``seconds`` (the returned timer does it)."""
        self.down()
        timer = threading.Timer(seconds, self.up)
        timer.start()
        return timer

    def close(self) -> None:
        self.down()
        self.sock.close()
        for s in self.held:
            s.close()

    def _accept(self) -> None:
        while True:
            try:
                client, _ = self.sock.accept()
            except OSError:
                return
            if self.mode == "down":
                client.close()
            elif self.mode == "silent":
                self.held.append(client)
            else:
                threading.Thread(target=self._connect, args=(client,), daemon=True).start()

    def _connect(self, client: socket.socket) -> None:
        try:
            server = socket.create_connection(("127.0.0.1", self.target_port))
        except OSError:
            client.close()
            return
        with self.lock:
            self.open.update((client, server))
        for a, b in ((client, server), (server, client)):
            threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    def _pipe(self, source: socket.socket, sink: socket.socket) -> None:
        try:
            while data := source.recv(65536):
                sink.sendall(data)
        except OSError:
            pass
        for s in (source, sink):
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)


class SilentListener:
    """Takes every connection and never answers (``with``: closed after)."""

    def __init__(self) -> None:
        self.proxy = FaultProxy(target_port=0)
        self.proxy.silent()

    @property
    def url(self) -> str:
        return self.proxy.url

    def __enter__(self) -> SilentListener:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.proxy.close()

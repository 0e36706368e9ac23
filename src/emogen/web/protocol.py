"""The HTTP protocol ``emogen serve`` runs: uvicorn's (httptools), with the request head bounded.

uvicorn's own protocol reads a request's line and headers without limit of size or time: one
64 MB header held a worker for seconds, and half-sent requests (a "slowloris") held their
connections for as long as the client liked, until no participant could connect. Here:

* a request head (request line + headers) over :data:`MAX_HEAD_BYTES` is answered
  ``431 Request Header Fields Too Large`` and the connection closed, once that much has
  arrived (never more than one read of the socket beyond it is held) — counted before the
  parser sees the bytes, whatever the read pattern (a whole 40 KB head in one read too);
* a head not complete :data:`HEAD_TIMEOUT_S` seconds after its first byte (or after the
  connection opened, for the first request) is answered ``408 Request Timeout`` and closed.

Between requests uvicorn's keep-alive timeout still closes idle connections. Both bounds come
from the environment (``EMOGEN_MAX_HEAD_BYTES``, ``EMOGEN_HEAD_TIMEOUT_S``, set by
``emogen serve --header-timeout``), read as each connection opens.
"""

from __future__ import annotations

import asyncio
import os

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

HEAD_TIMEOUT_ENV = "EMOGEN_HEAD_TIMEOUT_S"
MAX_HEAD_ENV = "EMOGEN_MAX_HEAD_BYTES"
#: Seconds a request's head may take to arrive (nginx's ``client_header_timeout`` is 60 s; a
#: participant's browser sends its < 2 KB of headers in one packet).
HEAD_TIMEOUT_S = 15.0
#: Bytes of request line and headers (the page's requests send under 2 KiB; nginx's default
#: ``large_client_header_buffers`` allows 4 × 8 KiB).
MAX_HEAD_BYTES = 32 * 1024
#: The import string uvicorn is given (it loads the class in each worker).
PROTOCOL = "emogen.web.protocol:BoundedHeadProtocol"


def head_bounds() -> tuple[float, int]:
    """(seconds, bytes) a request head may take: the environment's, else the defaults."""
    return (
        float(os.environ.get(HEAD_TIMEOUT_ENV, HEAD_TIMEOUT_S)),
        int(os.environ.get(MAX_HEAD_ENV, MAX_HEAD_BYTES)),
    )


def _answer(status: bytes, text: str) -> bytes:
    body = text.encode()
    return (
        b"HTTP/1.1 " + status + b"\r\ncontent-type: text/plain; charset=utf-8\r\n"
        b"content-length: " + str(len(body)).encode() + b"\r\nconnection: close\r\n\r\n" + body
    )


class BoundedHeadProtocol(HttpToolsProtocol):
    """uvicorn's httptools protocol with the size and the read time of request heads bounded."""

    _in_head = True
    _head_bytes = 0
    _tail = b""  # the last bytes of the head so far (its end may straddle two reads)
    _head_timer: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        self._timeout_s, self._max_bytes = head_bounds()
        super().connection_made(transport)
        self._start_head_timer()

    def connection_lost(self, exc: Exception | None) -> None:
        self._stop_head_timer()
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        if self._in_head:
            # counted before the parser sees it: a whole head in one read completes (and
            # would reset the count) inside the parser; its end is the first blank line
            seen = self._tail + data
            end = seen.find(b"\r\n\r\n")
            self._head_bytes += len(data) if end < 0 else end + 4 - len(self._tail)
            self._tail = seen[-3:]
            if self._head_timer is None:
                self._start_head_timer()
            if self._head_bytes > self._max_bytes:
                text = f"request headers over {self._max_bytes} bytes are not accepted"
                self._refuse(_answer(b"431 Request Header Fields Too Large", text))
                return
        super().data_received(data)

    def on_headers_complete(self) -> None:
        self._in_head = False
        self._head_bytes = 0
        self._tail = b""
        self._stop_head_timer()
        super().on_headers_complete()

    def on_message_complete(self) -> None:
        super().on_message_complete()
        self._in_head = True  # the next request's head: counted and timed from its first byte

    def _start_head_timer(self) -> None:
        self._stop_head_timer()
        self._head_timer = self.loop.call_later(self._timeout_s, self._head_timed_out)

    def _stop_head_timer(self) -> None:
        if self._head_timer is not None:
            self._head_timer.cancel()
            self._head_timer = None

    def _head_timed_out(self) -> None:
        self._head_timer = None
        if self._in_head:
            text = f"the request's headers did not arrive within {self._timeout_s:g} s"
            self._refuse(_answer(b"408 Request Timeout", text))

    def _refuse(self, answer: bytes) -> None:
        """Answer ``answer`` and close, unless an earlier request's answer is still being sent
        (then only close once it is: its keep-alive is off)."""
        self._stop_head_timer()
        self._in_head = False
        if self.transport.is_closing():
            return
        if self.cycle is not None and not self.cycle.response_complete:
            self.cycle.keep_alive = False
            return
        self.transport.write(answer)
        self.transport.close()

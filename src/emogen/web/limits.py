"""Request headers and limits: timing and security headers, and a cap on request bodies.

:class:`BodyLimit` answers 413 to a body over the limit before the app reads it: by its
``Content-Length``, or — for a chunked body — by counting while it buffers it.
"""

from __future__ import annotations

import asyncio
import json
import os
import time

from fastapi import FastAPI
from starlette.types import ASGIApp, Message, Receive, Scope, Send


class BodyLimit:
    """ASGI middleware: a request body over ``max_bytes`` gets 413 ``{"detail": …}``; one not
    complete ``timeout_s`` seconds after its head gets 408 and the connection is closed (a
    body trickled a byte at a time holds nothing longer). The body is read whole before the
    app sees it (at most ``max_bytes``), so a step is never stored from part of one."""

    def __init__(self, app: ASGIApp, max_bytes: int, timeout_s: float | None = None) -> None:
        self.app = app
        self.max_bytes = max_bytes
        self.timeout_s = body_timeout() if timeout_s is None else timeout_s

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        length = dict(scope["headers"]).get(b"content-length")
        if length is not None and (not length.isdigit() or int(length) > self.max_bytes):
            await self._refuse(send, 413, self._too_large(length.decode("latin-1")))
            return
        messages: list[Message] = []
        size = 0
        deadline = time.monotonic() + self.timeout_s
        while True:  # read (and count) the body before the app sees it
            try:
                message = await asyncio.wait_for(receive(), max(0.0, deadline - time.monotonic()))
            except TimeoutError:
                text = f"the request body did not arrive within {self.timeout_s:g} s"
                await self._refuse(send, 408, text)
                return
            messages.append(message)
            if message["type"] != "http.request":
                break
            size += len(message.get("body", b""))
            if size > self.max_bytes:
                await self._refuse(send, 413, self._too_large(f"more than {size}"))
                return
            if not message.get("more_body", False):
                break

        async def replay() -> Message:
            return messages.pop(0) if messages else await receive()

        await self.app(scope, replay, send)

    def _too_large(self, given: str) -> str:
        return f"request body must be at most {self.max_bytes} bytes; got {given}"

    async def _refuse(self, send: Send, status: int, detail: str) -> None:
        body = json.dumps({"detail": detail}).encode()
        headers = [
            (b"content-type", b"application/json"),
            (b"content-length", str(len(body)).encode()),
            (b"connection", b"close"),  # the rest of the body is never read
            *((k.lower().encode(), v.encode()) for k, v in SECURITY_HEADERS.items()),
        ]
        await send({"type": "http.response.start", "status": status, "headers": headers})
        await send({"type": "http.response.body", "body": body})


#: Seconds a request body may take to arrive after its head (``emogen serve --body-timeout``:
#: the environment variable the workers read). A step's body is under 2 KiB: it arrives with
#: its head; nginx's ``client_body_timeout`` is 60 s between reads.
BODY_TIMEOUT_ENV = "EMOGEN_BODY_TIMEOUT_S"
BODY_TIMEOUT_S = 20.0


def body_timeout() -> float:
    return float(os.environ.get(BODY_TIMEOUT_ENV, BODY_TIMEOUT_S))


#: The pages load only their own scripts and styles (no inline ones, no eval). The three.js
#: viewer decodes the GLB's textures through blob: URLs (img, fetch) and may use blob: workers;
#: the favicon is ``data:,``. Nothing may frame the pages (clickjacking).
CONTENT_SECURITY_POLICY = "; ".join(
    (
        "default-src 'self'",
        "script-src 'self'",
        "style-src 'self'",
        "img-src 'self' data: blob:",
        "connect-src 'self' data: blob:",
        "worker-src 'self' blob:",
        "object-src 'none'",
        "base-uri 'none'",
        "form-action 'self'",
        "frame-ancestors 'none'",
    )
)
SECURITY_HEADERS = {
    "Content-Security-Policy": CONTENT_SECURITY_POLICY,
    "X-Frame-Options": "DENY",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
}
#: HSTS value when the server is reached over HTTPS only (``hsts=True``): one year.
HSTS = "max-age=31536000; includeSubDomains"


class ResponseHeaders:
    """ASGI middleware: Server-Timing, CSP, no framing, nosniff, no referrer (session tokens
    are in URLs) on every answer; API answers are not cached; HSTS when ``hsts`` (behind TLS
    only). Plain ASGI, not ``@app.middleware("http")``: that wraps every response in a
    stream of its own, which costs the study step a share of its CPU (docs/study.md)."""

    def __init__(self, app: ASGIApp, hsts: bool = False) -> None:
        self.app = app
        fixed = dict(SECURITY_HEADERS)
        if hsts:
            fixed["Strict-Transport-Security"] = HSTS
        self.fixed = [(k.lower().encode("latin-1"), v.encode("latin-1")) for k, v in fixed.items()]

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        t0 = time.perf_counter()
        api = scope["path"].startswith("/api/")

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                ms = (time.perf_counter() - t0) * 1000
                ours = {k for k, _ in self.fixed} | {b"server-timing"}
                if api:
                    ours.add(b"cache-control")
                headers = [(k, v) for k, v in message.get("headers", []) if k.lower() not in ours]
                headers += self.fixed
                headers.append((b"server-timing", f"app;dur={ms:.2f}".encode("latin-1")))
                if api:
                    headers.append((b"cache-control", b"no-store"))
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, send_with_headers)


def add_response_headers(app: FastAPI, *, hsts: bool = False) -> None:
    """Adds :class:`ResponseHeaders` to ``app``."""
    app.add_middleware(ResponseHeaders, hsts=hsts)

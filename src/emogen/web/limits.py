"""Request headers and limits: timing and security headers, and a cap on request bodies.

:class:`BodyLimit` answers 413 to a body over the limit before the app reads it: by its
``Content-Length``, or — for a chunked body — by counting while it buffers it.
"""

from __future__ import annotations

import json
import time
from collections.abc import Awaitable, Callable

from fastapi import FastAPI, Request, Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send


class BodyLimit:
    """ASGI middleware: a request body over ``max_bytes`` gets 413 ``{"detail": …}``."""

    def __init__(self, app: ASGIApp, max_bytes: int) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        length = dict(scope["headers"]).get(b"content-length")
        if length is not None:
            if not length.isdigit() or int(length) > self.max_bytes:
                await self._too_large(send, length.decode("latin-1"))
                return
            await self.app(scope, receive, send)
            return
        messages: list[Message] = []
        size = 0
        while True:  # no length given: read (and count) the body before the app sees it
            message = await receive()
            messages.append(message)
            if message["type"] != "http.request":
                break
            size += len(message.get("body", b""))
            if size > self.max_bytes:
                await self._too_large(send, f"more than {size}")
                return
            if not message.get("more_body", False):
                break

        async def replay() -> Message:
            return messages.pop(0) if messages else await receive()

        await self.app(scope, replay, send)

    async def _too_large(self, send: Send, given: str) -> None:
        body = json.dumps(
            {"detail": f"request body must be at most {self.max_bytes} bytes; got {given}"}
        ).encode()
        headers = [
            (b"content-type", b"application/json"),
            (b"content-length", str(len(body)).encode()),
            *((k.lower().encode(), v.encode()) for k, v in SECURITY_HEADERS.items()),
        ]
        await send({"type": "http.response.start", "status": 413, "headers": headers})
        await send({"type": "http.response.body", "body": body})


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


def add_response_headers(app: FastAPI, *, hsts: bool = False) -> None:
    """Server-Timing, CSP, no framing, nosniff, no referrer (session tokens are in URLs) on
    every answer; API answers are not cached; HSTS when ``hsts`` (behind TLS only)."""

    @app.middleware("http")
    async def headers(
        request: Request, call_next: Callable[[Request], Awaitable[Response]]
    ) -> Response:
        t0 = time.perf_counter()
        response = await call_next(request)
        ms = (time.perf_counter() - t0) * 1000
        response.headers["Server-Timing"] = f"app;dur={ms:.2f}"
        response.headers.update(SECURITY_HEADERS)
        if hsts:
            response.headers["Strict-Transport-Security"] = HSTS
        if request.url.path.startswith("/api/"):
            response.headers["Cache-Control"] = "no-store"
        return response

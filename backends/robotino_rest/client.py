"""A small JSON-over-HTTP client for the Robotino REST API (urllib only).

Every request carries ``?sid=<name>`` as common clients do.  Failures
(connection refused, timeout, HTTP error status, bad JSON) raise
:class:`RestError`.
"""
from __future__ import annotations

import json
import urllib.error
import urllib.parse
import urllib.request


class RestError(OSError):
    """A request to the robot failed."""


class RestClient:
    def __init__(self, base_url: str = "http://127.0.0.1", *, timeout: float = 0.5,
                 sid: str | None = "rll_bt"):
        parsed = urllib.parse.urlparse(base_url)
        if parsed.scheme not in ("http", "https") or not parsed.netloc:
            raise ValueError(f"base URL must look like http://HOST[:PORT], got {base_url!r}")
        self.base_url = base_url.rstrip("/")
        self.timeout = timeout
        self.sid = sid

    def url(self, path: str) -> str:
        query = f"?{urllib.parse.urlencode({'sid': self.sid})}" if self.sid else ""
        return f"{self.base_url}/{path.lstrip('/')}{query}"

    def request(self, method: str, path: str, body=None) -> bytes:
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(self.url(path), data=data, method=method)
        if data is not None:
            req.add_header("Content-Type", "application/json")
        try:
            with urllib.request.urlopen(req, timeout=self.timeout) as resp:
                return resp.read()
        except urllib.error.HTTPError as exc:
            raise RestError(f"{method} {path}: HTTP {exc.code} {exc.reason}") from None
        except (urllib.error.URLError, OSError, ValueError) as exc:
            reason = getattr(exc, "reason", exc)
            raise RestError(f"{method} {path} at {self.base_url}: {reason}") from None

    def get_json(self, path: str):
        raw = self.request("GET", path)
        try:
            return json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as exc:
            raise RestError(f"GET {path}: not JSON ({exc})") from None

    def get_bytes(self, path: str) -> bytes:
        return self.request("GET", path)

    def send_json(self, path: str, body, method: str = "POST") -> None:
        self.request(method, path, body)

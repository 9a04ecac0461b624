"""``carnot explore``: a local web page for teaching, served on 127.0.0.1 only.

It serves exactly three things: its own page (``GET /``, HTML with its script and style inline:
nothing is fetched from elsewhere, so it works offline), the list of classics
(``GET /api/classics``) and carnot's answers (``POST /api/solve``). Nothing is read from disk
beyond the page shipped in the package. A request body is JSON of at most
``MAX_REQUEST_BYTES``; bad parameters are answered with HTTP 400 and the ``InputError``'s
message. The physics is carnot's: the scenario a classic builds goes through the same loader
(``carnot.io.scenario.parse_scenario``), solver (``carnot.solve_impact``) and result writer
(``carnot.io.results.result_to_dict``) as ``carnot solve FILE --json``.
"""

from __future__ import annotations

import json
import threading
import webbrowser
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any

import carnot
from carnot import CarnotError, InputError
from carnot.explore.classics import CLASSICS
from carnot.io.results import result_to_dict
from carnot.io.scenario import parse_scenario

HOST = "127.0.0.1"
MAX_REQUEST_BYTES = 4096
# The page may run its own inline script and talk to this server only.
CONTENT_SECURITY_POLICY = (
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
    "connect-src 'self'; img-src 'self' data:; base-uri 'none'; form-action 'none'"
)


def classics_catalogue() -> list[dict[str, Any]]:
    """The classics as plain data for the page: name, title, description, parameters.

    >>> [c["name"] for c in classics_catalogue()]
    ['cylinder_edge', 'rod_ledge', 'sphere_spin', 'cradle']
    """
    return [
        {
            "name": c.name,
            "title": c.title,
            "description": c.description,
            "parameters": [
                {"name": p.name, "label": p.label, "unit": p.unit, "default": p.default,
                 "low": p.low, "high": p.high, "step": p.step, "choices": list(p.choices)}
                for p in c.parameters
            ],  # fmt: skip
        }
        for c in CLASSICS.values()
    ]


def solve_request(request: Any) -> dict[str, Any]:
    """Answer one request ``{"classic": NAME, "parameters": {NAME: VALUE, ...}}``: the scenario
    it makes (format 1, as ``carnot solve`` reads it), the result (format 1, as
    ``carnot solve --json`` prints it) and, per contact, the impulse-space path of a frictional
    contact: rows ``[p, w_n, w_t1, w_t2, W_n, W_t]`` (N s, m/s, J; the result's
    ``process.samples``), ``null`` for a contact without Coulomb friction.

    >>> answer = solve_request({"classic": "rod_ledge", "parameters": {"mu": 0.0}})
    >>> round(answer["result"]["energy"]["dissipated"], 6), answer["paths"]
    (0.865385, [None])
    >>> solve_request({"classic": "rod_ledge", "parameters": {"e": 2}})
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: parameters.e: must be in [0.0, 1.0], got 2
    """
    if not isinstance(request, dict):
        raise InputError("request", "must be a JSON object", request)
    for key in request:
        if key not in ("classic", "parameters"):
            raise InputError(key, "unknown key (allowed: classic, parameters)", key)
    name = request.get("classic")
    if not isinstance(name, str) or name not in CLASSICS:
        raise InputError("classic", f"must be one of {', '.join(CLASSICS)}", name)
    scenario = CLASSICS[name].scenario(request.get("parameters", {}))
    problem = parse_scenario(scenario, "scenario")
    result = carnot.solve_impact(problem)
    paths = [
        None if o.process is None else _finite_rows(o.process.samples) for o in result.contacts
    ]
    return {"scenario": scenario, "result": result_to_dict(result), "paths": paths}


def _finite_rows(samples: Any) -> list[list[float | None]]:
    return [[float(x) if abs(float(x)) < float("inf") else None for x in row] for row in samples]


def _page() -> bytes:
    return resources.files("carnot.explore").joinpath("page.html").read_bytes()


class _Handler(BaseHTTPRequestHandler):
    server_version = "carnot-explore"
    sys_version = ""

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base's name
        pass  # a teaching page: no request log on the terminal

    def _send(self, status: int, body: bytes, content_type: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Content-Security-Policy", CONTENT_SECURITY_POLICY)
        self.end_headers()
        self.wfile.write(body)

    def _json(self, status: int, data: Any) -> None:
        body = json.dumps(data, allow_nan=False).encode("utf-8")
        self._send(status, body, "application/json")

    def _host_ok(self) -> bool:
        # Only this machine's own names: a page elsewhere that rebinds its name to 127.0.0.1
        # (DNS rebinding) sends its own Host header and is refused.
        port = getattr(self.server, "server_port", None)  # set by HTTPServer.server_bind
        return self.headers.get("Host", "") in (f"{HOST}:{port}", f"localhost:{port}")

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        if not self._host_ok():
            self._json(HTTPStatus.FORBIDDEN, {"error": "unknown Host header"})
        elif self.path in ("/", "/index.html"):
            self._send(HTTPStatus.OK, _page(), "text/html; charset=utf-8")
        elif self.path == "/api/classics":
            self._json(HTTPStatus.OK, classics_catalogue())
        else:
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no such page: {self.path[:80]}"})

    def do_POST(self) -> None:  # noqa: N802
        if not self._host_ok():
            self._json(HTTPStatus.FORBIDDEN, {"error": "unknown Host header"})
            return
        if self.path != "/api/solve":
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no such endpoint: {self.path[:80]}"})
            return
        try:
            length = int(self.headers.get("Content-Length", ""))
        except ValueError:
            self._json(HTTPStatus.LENGTH_REQUIRED, {"error": "Content-Length is required"})
            return
        if not 0 <= length <= MAX_REQUEST_BYTES:
            self.close_connection = True  # the body is not read
            self._json(
                HTTPStatus.REQUEST_ENTITY_TOO_LARGE,
                {"error": f"request: must be at most {MAX_REQUEST_BYTES} bytes, got {length}"},
            )
            return
        try:
            request = json.loads(self.rfile.read(length).decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as err:
            self._json(HTTPStatus.BAD_REQUEST, {"error": f"request: not JSON ({err})"})
            return
        try:
            answer = solve_request(request)
        except CarnotError as err:
            self._json(HTTPStatus.BAD_REQUEST, {"error": " ".join(str(err).splitlines())})
            return
        self._json(HTTPStatus.OK, answer)

    def do_PUT(self) -> None:  # noqa: N802
        self._json(HTTPStatus.METHOD_NOT_ALLOWED, {"error": "only GET and POST"})

    do_DELETE = do_PATCH = do_PUT


def make_server(port: int = 0) -> ThreadingHTTPServer:
    """A server on 127.0.0.1 at ``port`` (0: any free port), not yet serving.

    >>> server = make_server()
    >>> server.server_address[0]
    '127.0.0.1'
    >>> server.server_close()
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise InputError("--port", "must be an integer in [0, 65535]", port)
    try:
        return ThreadingHTTPServer((HOST, port), _Handler)
    except OSError as err:
        raise InputError("--port", f"cannot listen there ({err.strerror})", port) from None


def serve(port: int = 8765, *, open_browser: bool = True) -> None:
    """Serve the page until interrupted (Ctrl-C), opening it in the browser unless told not."""
    server = make_server(port)
    url = f"http://{HOST}:{server.server_address[1]}/"
    print(f"carnot explore: {url} (Ctrl-C to stop)", flush=True)
    if open_browser:
        threading.Timer(0.3, webbrowser.open, args=(url,)).start()
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()

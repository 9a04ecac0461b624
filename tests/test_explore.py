"""carnot explore: the classics (against published closed forms), the JSON endpoint and the
server's limits (127.0.0.1 only, its own page and answers only, size limits, HTTP 400 with
the InputError's message)."""

from __future__ import annotations

import http.client
import json
import threading
from collections.abc import Iterator

import pytest

from carnot.cli import main
from carnot.errors import InputError
from carnot.explore import CLASSICS, make_server, solve_request
from carnot.explore.server import MAX_REQUEST_BYTES


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_cradle_three_balls_is_the_simultaneous_newton_closed_form(e) -> None:
    """Three equal balls, the first at v: every contact at once with Newton's e (generalized
    Newton; Glocker, *Set-Valued Force Laws*, 2001; the three-ball cradle of issue 14):
    ((1 - 2e)/3, (1 + e)/3, (1 + e)/3) v."""
    v = 1.5
    result = solve_request({"classic": "cradle", "parameters": {"e": e, "speed": v}})["result"]
    velocities = [result["bodies"][f"ball{k}"]["velocity"][0] for k in (1, 2, 3)]
    expected = [(1 - 2 * e) / 3 * v, (1 + e) / 3 * v, (1 + e) / 3 * v]
    assert velocities == pytest.approx(expected, rel=1e-12, abs=1e-12)
    energy = result["energy"]
    assert energy["dissipated"] == pytest.approx(energy["dissipated_theorem"], abs=1e-12)


@pytest.mark.parametrize("d", [-0.4, 0.0, 0.3])
def test_rod_ledge_frictionless_is_the_effective_mass_closed_form(d) -> None:
    """A rod (m, L = 1) falling flat at v onto a ledge at d (Stronge, *Impact Mechanics*, 2000,
    ch. 2-3): P = (1 + e) m v / (1 + 12 d^2), E_d = (1 - e^2) m v^2 / (2 (1 + 12 d^2))."""
    m, v, e = 1.2, 2.0, 0.4
    answer = solve_request({"classic": "rod_ledge",
                            "parameters": {"d": d, "drop": v, "e": e, "mu": 0.0, "slide": 0.0}})
    result = answer["result"]  # fmt: skip
    assert result["contacts"][0]["normal_impulse"] == pytest.approx(
        (1 + e) * m * v / (1 + 12 * d**2), rel=1e-9
    )
    assert result["energy"]["dissipated"] == pytest.approx(
        (1 - e**2) * m * v**2 / (2 * (1 + 12 * d**2)), rel=1e-9
    )
    assert answer["paths"] == [None]  # frictionless: no impulse-space process


def test_cylinder_edge_defaults_are_the_papers_section_3_1_normal_impulse() -> None:
    """The paper's section 3.1 (m = 2, v'_O = 2): P_n = m v'_O (1 + e) cos(alpha), whatever the
    friction does to the tangential impulse (the normal row is uncoupled here: the contact
    normal passes through the centre)."""
    import math

    answer = solve_request({"classic": "cylinder_edge", "parameters": {"e": 0.5}})
    p_n = answer["result"]["contacts"][0]["normal_impulse"]
    assert p_n == pytest.approx(2 * 2.0 * 1.5 * math.cos(math.radians(37.0)), rel=1e-9)
    path = answer["paths"][0]
    assert path[0][0] == 0.0 and path[-1][0] == pytest.approx(p_n, rel=1e-12)


def test_sphere_spin_grip_is_the_rolling_closed_form() -> None:
    """Ball with backspin (m, R; v_x = 3, v_z = -4, omega_y = -50): with enough friction the slip
    stops and it leaves rolling, v''_x = (5 v_x + 2 R omega_y) / 7 (angular momentum about the
    contact point conserved; Cross, Am. J. Phys. 70, 2002; Brody, Am. J. Phys. 52, 1984)."""
    result = solve_request({"classic": "sphere_spin", "parameters": {"mu": 1.0}})["result"]
    assert result["contacts"][0]["regime"] == "slip-stick"
    assert result["bodies"]["ball"]["velocity"][0] == pytest.approx(
        (5 * 3.0 + 2 * 0.04 * -50.0) / 7, rel=1e-12
    )


@pytest.mark.parametrize("name", list(CLASSICS))
def test_every_classic_answers_as_carnot_solve_does(name, tmp_path, capsys) -> None:
    """The endpoint's result is what `carnot solve FILE --json` prints for its scenario."""
    answer = solve_request({"classic": name})
    path = tmp_path / "scenario.json"
    path.write_text(json.dumps(answer["scenario"]), encoding="utf-8")
    assert main(["solve", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == answer["result"]


@pytest.mark.parametrize(
    ("request_", "message"),
    [
        ({"classic": "rod_ledge", "parameters": {"e": 1.5}},
         "parameters.e: must be in [0.0, 1.0], got 1.5"),
        ({"classic": "rod_ledge", "parameters": {"mu": "lots"}},
         "parameters.mu: must be a number, got 'lots'"),
        ({"classic": "rod_ledge", "parameters": {"law": "hooke"}},
         "parameters.law: must be one of newton, poisson, stronge, got 'hooke'"),
        ({"classic": "cradle", "parameters": {"balls": 50}},
         "parameters.balls: must be in [2.0, 5.0], got 50"),
        ({"classic": "pendulum"}, "classic: must be one of cylinder_edge, rod_ledge"),
        ({"classic": "cradle", "extra": 1}, "extra: unknown key"),
        ([1, 2], "request: must be a JSON object"),
    ],
)  # fmt: skip
def test_bad_requests_name_the_field(request_, message) -> None:
    with pytest.raises(InputError, match=None) as err:
        solve_request(request_)
    assert str(err.value).startswith(message)


@pytest.fixture
def server() -> Iterator[int]:
    srv = make_server(0)
    thread = threading.Thread(target=srv.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    yield srv.server_address[1]
    srv.shutdown()
    srv.server_close()


def _ask(port: int, method: str, path: str, body: bytes | None = None,
         headers: dict[str, str] | None = None) -> tuple[int, dict[str, str], bytes]:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    connection.request(method, path, body=body, headers=headers or {})
    response = connection.getresponse()
    data = response.read()
    connection.close()
    return response.status, dict(response.getheaders()), data  # fmt: skip


def test_server_binds_loopback_only(server) -> None:
    with pytest.raises(InputError, match="--port: must be an integer in"):
        make_server(70000)


def test_page_is_self_contained(server) -> None:
    status, headers, page = _ask(server, "GET", "/")
    assert status == 200 and headers["Content-Type"].startswith("text/html")
    assert "default-src 'none'" in headers["Content-Security-Policy"]
    text = page.decode("utf-8")
    # Offline: no script, style or picture from elsewhere.
    assert "<script src" not in text and "<link" not in text and "@import" not in text
    assert "https://" not in text


def test_solve_endpoint_and_its_errors(server) -> None:
    good = json.dumps({"classic": "cradle", "parameters": {"e": 1.0}}).encode()
    status, _, body = _ask(server, "POST", "/api/solve", good)
    assert status == 200
    assert json.loads(body)["result"]["bodies"]["ball3"]["velocity"][0] == pytest.approx(2 / 3)
    bad = json.dumps({"classic": "cradle", "parameters": {"e": -1}}).encode()
    status, _, body = _ask(server, "POST", "/api/solve", bad)
    assert status == 400
    assert json.loads(body) == {"error": "parameters.e: must be in [0.0, 1.0], got -1"}
    status, _, body = _ask(server, "POST", "/api/solve", b"{not json")
    assert status == 400 and json.loads(body)["error"].startswith("request: not JSON")
    status, _, _ = _ask(server, "POST", "/api/solve", b" " * (MAX_REQUEST_BYTES + 1))
    assert status == 413


@pytest.mark.parametrize("path", ["/etc/passwd", "/../pyproject.toml", "/page.html", "/api"])
def test_nothing_else_is_served(server, path) -> None:
    status, _, _ = _ask(server, "GET", path)
    assert status == 404


def test_other_hosts_are_refused(server) -> None:
    """A page elsewhere whose name was rebound to 127.0.0.1 sends its own Host header."""
    status, _, _ = _ask(server, "GET", "/", headers={"Host": "evil.example:80"})
    assert status == 403
    status, _, _ = _ask(server, "GET", "/api/classics")
    assert status == 200


def test_cli_bad_port_exits_2_with_one_line(capsys) -> None:
    assert main(["explore", "--port", "99999", "--no-browser"]) == 2
    err = capsys.readouterr().err
    assert err == "carnot: error: --port: must be an integer in [0, 65535], got 99999\n"

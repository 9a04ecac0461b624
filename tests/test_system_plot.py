"""``carnot solve FILE --plot`` on [system] results (DESIGN.md section 7): a frictional
contact's impulse-space history, and several contacts' laws side by side, drawn from the
system's own result, checked against closed forms.

* Kane and Levinson's double pendulum (examples/systems/): the slip speed drawn falls
  linearly in the normal impulse with the planar slope ``K_tn - mu K_tt`` (Stronge, *Impact
  Mechanics*, 2000, ch. 5), from the system's ``K = J M^-1 J^T`` in the contact frame, and
  stops at ``p = |w'_t| / (mu K_tt - K_tn)``.
* A uniform rod (1 kg, 1 m) landing flat on both ends, ``y' = -1`` m/s and ``phi' = 0.5``
  rad/s: the ends strike at ``-1.25`` and ``-0.75`` m/s, and the simultaneous Newton law
  (``e = 0.5``) sends them back at ``0.625`` and ``0.375``: ``y'' = 0.5``, ``phi'' = -0.25``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from carnot import solve_impact
from carnot.cli import main
from carnot.io.scenario import load_problem
from carnot.model.system import System, SystemContact, SystemProblem
from carnot.plot import plot_impact
from carnot.plot_several import plot_laws

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "systems"


def _png(path: Path) -> bool:
    return path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10_000


def test_plot_of_a_frictional_system_contact(tmp_path: Path, capsys) -> None:
    source = EXAMPLES / "kane_levinson_double_pendulum.toml"
    out = tmp_path / "kl.png"
    assert main(["solve", str(source), "--plot", str(out)]) == 0
    assert _png(out)
    problem = load_problem(source)
    assert isinstance(problem, SystemProblem)
    result = solve_impact(problem)
    fig = plot_impact(result)
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    slip = next(ln for name, ln in lines.items() if name.startswith("slip along"))
    p, speed = np.asarray(slip.get_xdata()), np.asarray(slip.get_ydata())
    # the system's K in the contact's frame (n, t along the initial slip)
    c = problem.contacts[0]
    m_inv = np.linalg.inv(problem.system.mass_matrix)
    w0 = c.jacobian @ problem.system.velocity
    n = c.contact.normal
    t = (w0 - (w0 @ n) * n) / np.linalg.norm(w0 - (w0 @ n) * n)
    k = np.array([[a @ c.jacobian @ m_inv @ c.jacobian.T @ b for b in (n, t)] for a in (n, t)])
    slope = k[1, 0] - c.friction * k[1, 1]  # d(w . t)/dp while slipping along t
    sliding = speed > 1e-9
    assert np.allclose(np.diff(speed[sliding]) / np.diff(p[sliding]), slope, rtol=1e-9)
    assert speed[0] == pytest.approx(np.linalg.norm(w0 - (w0 @ n) * n), rel=1e-12)
    # the slip stops where the straight line reaches zero, and the drawing turns there
    stop = speed[0] / -slope
    assert result.contacts[0].process.phases[1].start == pytest.approx(stop, rel=1e-12)
    assert p[sliding][-1] <= stop <= p[~sliding][0]


def test_plot_of_several_system_contacts(tmp_path: Path) -> None:
    rod = SystemProblem(
        title="A rod lands flat on both ends",
        system=System(mass_matrix=np.diag([1.0, 1.0, 1 / 12]), velocity=[0.2, -1.0, 0.5],
                      coordinates=("x", "y", "phi")),
        contacts=[SystemContact(jacobian=[[1, 0, 0], [0, 1, s * 0.5], [0, 0, 0]],
                                normal=[0, 1, 0], restitution=0.5, name=name)
                  for s, name in ((-1, "left"), (1, "right"))],
    )  # fmt: skip
    fig = plot_laws(rod, tmp_path / "rod.png")
    assert _png(tmp_path / "rod.png")
    bars = fig.axes[0].containers[0]  # the simultaneous law's q''
    assert bars.get_label() == "simultaneous"
    assert [b.get_height() for b in bars] == pytest.approx([0.2, 0.5, -0.25], abs=1e-12)
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == ["x", "y", "phi"]


def test_plot_of_a_system_without_friction_says_what_it_needs(tmp_path: Path, capsys) -> None:
    out = tmp_path / "cg.png"
    assert main(["solve", str(EXAMPLES / "compass_gait.toml"), "--plot", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs a contact with Coulomb friction" in err
    assert not out.exists()

"""Write the many-contact examples of this folder as scenario files (format 1).

The scenes are built by ``tests/scenes.py`` (the same builders the solver tests and
``benchmarks/bench_many_contacts.py`` use); this script writes each one out as plain data,
every body with its mass, inertia tensor, position and velocities, every contact with its
point, normal, restitution and friction, so that ``carnot solve FILE`` reads it like any
scenario. Run from the repository root: ``.venv/bin/python examples/many/generate.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))
from scenes import cradle, poured, table, tower, wall  # noqa: E402

from carnot import FixedBody, ImpactProblem  # noqa: E402

EXAMPLES = {
    "tower_of_10_boxes.toml": (lambda: tower(10, rng=np.random.default_rng(4)),
                               "Ten boxes stacked corner on corner land on a floor: 40 "
                               "frictional contacts (mu = 0.5), far beyond the enumeration's "
                               "4096 regimes: the iterative solver."),
    "brick_wall.toml": (lambda: wall(4, 5), "A 4 x 5 brick wall on a floor struck at its "
                        "middle by a 2 kg ball at 5 m/s: 75 frictional contacts."),
    "spheres_poured_into_a_box.toml": (lambda: poured(100), "100 spheres poured into a box, "
                                       "at the instant the last layer lands: 300 contacts, "
                                       "jammed in columns, where ADMM stalls: the iterative "
                                       "solver's proximal point stage answers in about 570 "
                                       "iterations (it took 26000 before, some 30 s)."),
    "cradle_100.toml": (lambda: cradle(100, e=1.0), "A cradle of 100 balls, e = 1: Glocker's "
                        "closed form (2001), v1'' = (1 - 99 e)/100 v, the others (1 + e)/100 v."),
    "table_on_uneven_ground.toml": (lambda: table(), "A table lands on four legs on uneven "
                                    "ground (each foot's patch tilted its own way), mu = 0.15: "
                                    "4 contacts, enumerated (81 regimes); three legs slip, one "
                                    "lifts. With mu = 0.3 all four stick and the table stops, "
                                    "its impulse split among the legs not unique."),
}


def _number(x: float) -> str:
    return repr(float(x)).replace("inf", "1e999")


def _vector(v: object) -> str:
    return "[" + ", ".join(_number(x) for x in np.asarray(v, dtype=float).reshape(-1)) + "]"


#: A [solver] table for the examples that need more than the default budget (none now: the
#: poured spheres took 26000 iterations before the proximal point stage, 570 since).
SOLVER: dict[str, str] = {}


def scenario_toml(problem: ImpactProblem, comment: str, solver: str = "") -> str:
    """``problem`` as a format-1 scenario (free bodies and point contacts), with a
    ``[solver]`` table's text ``solver`` when given."""
    lines = [f"# {line}" for line in _wrap(comment)]
    lines += ["# Written by examples/many/generate.py from tests/scenes.py.", "format = 1",
              f"title = {problem.title!r}".replace("'", '"'), "", solver]  # fmt: skip
    for name, body in problem.bodies.items():
        lines.append(f"[bodies.{name}]")
        if isinstance(body, FixedBody):
            lines += ["fixed = true", ""]
            continue
        inertia = ", ".join(_vector(row) for row in body.inertia_com)
        lines += [f"mass = {_number(body.mass)}", f"inertia = [{inertia}]",
                  f"position = {_vector(body.position_com)}",
                  f"velocity = {_vector(body.velocity_com)}",
                  f"angular_velocity = {_vector(body.angular_velocity)}", ""]  # fmt: skip
    for contact in problem.contacts:
        lines += ["[[contacts]]", f'name = "{contact.where}"', f'a = "{contact.a}"',
                  f'b = "{contact.b}"', f"point = {_vector(contact.point)}",
                  f"normal = {_vector(contact.normal)}",
                  f"restitution = {_number(contact.restitution)}"]  # fmt: skip
        if contact.friction:
            lines.append(f"friction = {_number(contact.friction)}")
        lines.append("")
    return "\n".join(lines)


def _wrap(text: str, width: int = 96) -> list[str]:
    out, line = [], ""
    for word in text.split():
        if len(line) + len(word) + 1 > width:
            out.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    return [*out, line]


def main() -> None:
    for name, (build, comment) in EXAMPLES.items():
        path = Path(__file__).parent / name
        path.write_text(scenario_toml(build(), comment, SOLVER.get(name, "")))
        print(path.relative_to(ROOT))


if __name__ == "__main__":
    main()

"""Several contacts in independent groups: the law on each group alone (now) against the law on
the whole contact space (before), in the same run.

The scene: ten bodies on a floor, 24 contacts in eight independent groups: four boxes (2 kg,
0.4 x 0.3 x 0.2 m) landing on their four corners at 0.05-0.2 m/s, slightly rocking, three balls
dropped into V-grooves (two walls each) and a three-ball Newton's cradle. "before" is the law
called once on the whole contact space (``G`` 24 x 24 frictionless, 72 x 72 with Coulomb
friction), and its answer mapped back, exactly as ``carnot.several.resolve_several`` did
before the split (its path for one group: ``_solve_group`` on every item, then ``_mapped``);
"after" is ``resolve_several`` (the groups found, each solved alone, the answers put
together). Both on the same prebuilt contact space, each the median of ``--repeat`` calls
after a warm-up; the whole ``solve_impact`` (assembly and outcome included) for scale. A
smaller scene (two boxes and two grooves, 12 frictionless contacts: 2^12 = 4096 regimes in
all, the cap) gives the simultaneous law a "before" that runs.

Run: ``.venv/bin/python benchmarks/bench_several_groups.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import math
import platform

import numpy as np
from timing import summary, timed

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.errors import InputError
from carnot.model.free_bodies import assemble
from carnot.several import Several, _mapped, _solve_group, independent_groups, resolve_several

Group = tuple[dict[str, RigidBody], list[PointContact]]


def box(name: str, x: float, vz: float, omega: tuple[float, float, float], mu: float) -> Group:
    m, (a, b, c) = 2.0, (0.4, 0.3, 0.2)
    inertia = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    body = RigidBody(name=name, mass=m, inertia_com=inertia, position_com=[x, 0, c / 2],
                     velocity_com=[0.1, 0.0, vz], angular_velocity=list(omega))  # fmt: skip
    corners = ((1, 1), (-1, 1), (-1, -1), (1, -1))
    return {name: body}, [
        PointContact(a=name, b="floor", point=[x + sx * a / 2, sy * b / 2, 0.0],
                     normal=[0, 0, 1], restitution=0.2, friction=mu, where=f"{name}-{k}")
        for k, (sx, sy) in enumerate(corners)
    ]  # fmt: skip


def groove_ball(name: str, x: float, vz: float, mu: float) -> Group:
    r, m, t = 0.1, 1.0, math.radians(40.0)
    centre = np.array([x, 2.0, 0.5])
    body = RigidBody(name=name, mass=m, inertia_com=np.eye(3) * 0.4 * m * r * r,
                     position_com=centre, velocity_com=[0.3, 0.1, vz])  # fmt: skip
    contacts = []
    for k, s in enumerate((1, -1)):
        n = np.array([0.0, -s * math.cos(t), math.sin(t)])
        contacts.append(PointContact(a=name, b="floor", point=centre - r * n, normal=n,
                                     restitution=0.5, friction=mu,
                                     where=f"{name}-{k}"))  # fmt: skip
    return {name: body}, contacts


def cradle() -> Group:
    bodies = {n: RigidBody(name=n, mass=1.0, inertia_com=np.eye(3) * 0.1,
                           position_com=[k, 4.0, 5.0], velocity_com=[2.0 if k == 0 else 0, 0, 0])
              for k, n in enumerate("ABC")}  # fmt: skip
    contacts = [PointContact(a="B", b="A", point=[0.5, 4.0, 5.0], normal=[1, 0, 0],
                             restitution=0.9, where="AB"),
                PointContact(a="C", b="B", point=[1.5, 4.0, 5.0], normal=[1, 0, 0],
                             restitution=0.9, where="BC")]  # fmt: skip
    return bodies, contacts


def scene(
    law: str, mu: float, boxes: int = 4, grooves: int = 3, chain: bool = True
) -> ImpactProblem:
    groups = [box(f"box{k}", 2.0 * k, -0.05 * (k + 1), (0.05 * k, -0.03, 0.1), mu)
              for k in range(boxes)]  # fmt: skip
    groups += [groove_ball(f"ball{k}", 2.0 * k, -1.0 - k, mu) for k in range(grooves)]
    if chain:
        groups.append(cradle())
    bodies: dict = {"floor": FixedBody(name="floor")}
    contacts: list[PointContact] = []
    for b, c in groups:
        bodies.update(b)
        contacts.extend(c)
    return ImpactProblem(bodies=bodies, contacts=contacts, multiple_impact=law)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    print(f"python {platform.python_version()}, numpy {np.__version__}")
    cases = [
        ("simultaneous, frictionless, 24 contacts", scene("simultaneous", 0.0)),
        ("simultaneous, mu = 0.5, 24 contacts", scene("simultaneous", 0.5)),
        ("simultaneous, frictionless, 12 contacts",
         scene("simultaneous", 0.0, boxes=2, grooves=2, chain=False)),
        ("sequential, 24 contacts", scene("sequential", 0.0)),
        ("dispersion, 24 contacts", scene("dispersion", 0.0)),
    ]  # fmt: skip
    print(f"{'case':42s} {'groups':>6s} {'before':>12s} {'after':>12s} {'ratio':>7s} "
          f"{'solve_impact':>13s}")  # fmt: skip
    for name, problem in cases:
        items = list(problem.contacts)
        space = assemble(problem, items, [c.rows() for c in items]).space
        everything = list(range(len(items)))
        groups = len(independent_groups(space, everything))
        w = space.row_velocities(space.u_before)
        law = problem.multiple_impact

        def before(items=items, space=space, law=law, w=w, everything=everything) -> Several:
            whole = _solve_group(items, space, law, everything, w, space.u_before)
            return _mapped(whole.answer, items, space, np.zeros(space.size), whole.rows,
                           whole.owners)  # fmt: skip

        def after(items=items, space=space, law=law) -> object:
            return resolve_several(items, space, law, [])

        repeat = max(3, args.repeat // 4) if law == "dispersion" else args.repeat
        try:
            t_before = summary(timed(before, repeat, warm_up=1))[0]
            shown = f"{t_before * 1e3:9.2f} ms"
        except InputError as err:
            t_before, shown = math.nan, "refused"
            note = str(err)
        t_after = summary(timed(after, repeat, warm_up=1))[0]
        t_whole = summary(timed(lambda p=problem: solve_impact(p), repeat, warm_up=1))[0]
        ratio = f"{t_before / t_after:6.1f}x" if t_before == t_before else "      -"
        print(f"{name:42s} {groups:6d} {shown:>12s} {t_after * 1e3:9.2f} ms {ratio} "
              f"{t_whole * 1e3:10.2f} ms")  # fmt: skip
        if t_before != t_before:
            print(f"  before: {note}")
            continue
        old, new = before(), after()[1]
        diff = float(np.max(np.abs(old.impulses - new.impulses)))
        print(f"  largest row impulse difference before/after: {diff:.1e} N s; alternatives "
              f"{len(old.alternatives)} / {len(new.alternatives)}, stages {len(old.stages)} / "
              f"{len(new.stages)}")  # fmt: skip


if __name__ == "__main__":
    main()

"""Scenes of many coupled contacts built with carnot's public model: a tower of boxes landing
on a floor, a brick wall struck by a ball, a pile of spheres in a box, an N-ball cradle.

Used by the tests of the contact solvers and by ``benchmarks/bench_many_contacts.py``; each
returns an :class:`~carnot.ImpactProblem` whose contacts are all closed (touching) at the
instant, with random pre-impact velocities where ``rng`` is given.
"""

from __future__ import annotations

import numpy as np

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody
from carnot.model.inertia import box as box_inertia
from carnot.model.inertia import solid_sphere

_CORNERS = ((1, 1), (-1, 1), (-1, -1), (1, -1))


def tower(boxes: int, *, mu: float = 0.5, e: float = 0.0, size=(0.4, 0.3, 0.2),
          v_land: float = -1.0,
          rng: np.random.Generator | None = None) -> ImpactProblem:  # fmt: skip
    """``boxes`` boxes (2 kg each) stacked corner on corner, the bottom one on a floor, all
    falling at ``v_land`` (m/s) with small random velocities and spins where ``rng`` is
    given: four contacts per box (``4 boxes`` in all), each with ``mu`` and ``e``."""
    a, b, c = size
    bodies: dict[str, RigidBody | FixedBody] = {"floor": FixedBody(name="floor")}
    contacts = []
    for k in range(boxes):
        name = f"box{k}"
        v = np.array([0.0, 0.0, v_land * (1.0 + 0.1 * k)])
        w = np.zeros(3)
        if rng is not None:
            v = v + rng.normal(0.0, 0.2, 3)
            w = rng.normal(0.0, 0.5, 3)
        bodies[name] = RigidBody(name=name, mass=2.0, inertia_com=box_inertia(2.0, size),
                                 position_com=[0.0, 0.0, c / 2 + k * c], velocity_com=v,
                                 angular_velocity=w)  # fmt: skip
        below = "floor" if k == 0 else f"box{k - 1}"
        for j, (sx, sy) in enumerate(_CORNERS):
            contacts.append(PointContact(a=name, b=below, point=[sx * a / 2, sy * b / 2, k * c],
                                         normal=[0, 0, 1], restitution=e, friction=mu,
                                         where=f"{name}-{j}"))  # fmt: skip
    return ImpactProblem(bodies=bodies, contacts=contacts, title=f"A tower of {boxes} boxes")


def wall(rows: int, columns: int, *, mu: float = 0.6, e: float = 0.2,
         ball_speed: float = 5.0) -> ImpactProblem:  # fmt: skip
    """A brick wall (``rows`` courses of ``columns`` bricks, 0.2 x 0.1 x 0.1 m, 1 kg, each
    course offset by half a brick) on a floor, struck at its middle by a 2 kg ball at
    ``ball_speed`` along +y: two contacts under every brick end, the ball on one brick."""
    length, depth, height = 0.2, 0.1, 0.1
    bodies: dict[str, RigidBody | FixedBody] = {"floor": FixedBody(name="floor")}
    contacts = []
    centres: dict[tuple[int, int], float] = {}
    for i in range(rows):
        offset = 0.0 if i % 2 == 0 else length / 2
        for j in range(columns):
            x = offset + j * length
            centres[i, j] = x
            name = f"brick{i}_{j}"
            bodies[name] = RigidBody(name=name, mass=1.0,
                                     inertia_com=box_inertia(1.0, (length, depth, height)),
                                     position_com=[x, 0.0, height / 2 + i * height])  # fmt: skip
            z = i * height
            for sx in (-1, 1):
                for sy in (-1, 1):
                    px = x + sx * length / 2 * 0.999
                    if i == 0:
                        below = "floor"
                    else:
                        below_j = [jj for jj in range(columns)
                                   if abs(centres[i - 1, jj] - px) < length / 2]  # fmt: skip
                        if not below_j:
                            continue
                        below = f"brick{i - 1}_{below_j[0]}"
                    contacts.append(PointContact(
                        a=name, b=below, point=[px, sy * depth / 2, z], normal=[0, 0, 1],
                        restitution=e, friction=mu, where=f"{name}/{below}/{sx}{sy}"))  # fmt: skip
    target = f"brick{rows // 2}_{columns // 2}"
    tx = centres[rows // 2, columns // 2]
    radius = 0.05
    bodies["ball"] = RigidBody(name="ball", mass=2.0, inertia_com=solid_sphere(2.0, radius),
                               position_com=[tx, -depth / 2 - radius, (rows // 2 + 0.5) * height],
                               velocity_com=[0.0, ball_speed, 0.0])  # fmt: skip
    contacts.append(PointContact(a=target, b="ball", point=[tx, -depth / 2, (rows // 2 + 0.5)
                                                            * height], normal=[0, 1, 0],
                                 restitution=e, friction=mu, where="ball/" + target))  # fmt: skip
    return ImpactProblem(bodies=bodies, contacts=contacts, title="A brick wall struck by a ball")


def cradle(balls: int, *, e: float = 1.0, speed: float = 1.0) -> ImpactProblem:
    """``balls`` equal steel balls (0.1 kg, radius 0.02 m) touching in a row along x, the first
    striking the others at ``speed`` (m/s); frictionless, ``e`` at every contact."""
    r, m = 0.02, 0.1
    bodies = {f"ball{k}": RigidBody(name=f"ball{k}", mass=m, inertia_com=solid_sphere(m, r),
                                    position_com=[2 * r * k, 0.0, 0.0],
                                    velocity_com=[speed if k == 0 else 0.0, 0.0, 0.0])
              for k in range(balls)}  # fmt: skip
    contacts = [PointContact(a=f"ball{k + 1}", b=f"ball{k}", point=[2 * r * k + r, 0.0, 0.0],
                             normal=[1, 0, 0], restitution=e, where=f"{k}-{k + 1}")
                for k in range(balls - 1)]  # fmt: skip
    return ImpactProblem(bodies=bodies, contacts=contacts, title=f"A cradle of {balls} balls")


def pile(spheres: int, *, mu: float = 0.4, e: float = 0.3, seed: int = 0) -> ImpactProblem:
    """``spheres`` equal spheres (0.1 kg, radius 0.05 m) in a square-packed pile on a floor,
    layer on layer (each sphere above a layer rests on the four below it, the bottom layer on
    the floor), all falling with random velocities and spins (``seed``)."""
    rng = np.random.default_rng(seed)
    r, m = 0.05, 0.1
    bodies: dict[str, RigidBody | FixedBody] = {"floor": FixedBody(name="floor")}
    contacts: list[PointContact] = []
    side = max(2, int(np.ceil(np.sqrt(spheres / 2.0))))
    placed: dict[tuple[int, int, int], np.ndarray] = {}
    layer = 0
    count = 0
    dz = r * np.sqrt(2.0)
    while count < spheres:
        n = side - layer
        if n < 1:
            layer, side = 0, side + 1  # (never reached with the size above)
            continue
        for i in range(n):
            for j in range(n):
                if count == spheres:
                    break
                centre = np.array([(2 * i + layer) * r, (2 * j + layer) * r, r + layer * dz])
                name = f"s{count}"
                bodies[name] = RigidBody(name=name, mass=m, inertia_com=solid_sphere(m, r),
                                         position_com=centre,
                                         velocity_com=rng.normal(0.0, 0.3, 3) + [0, 0, -1.0],
                                         angular_velocity=rng.normal(0.0, 2.0, 3))  # fmt: skip
                placed[layer, i, j] = centre
                if layer == 0:
                    contacts.append(PointContact(a=name, b="floor", point=centre - [0, 0, r],
                                                 normal=[0, 0, 1], restitution=e, friction=mu,
                                                 where=f"{name}/floor"))  # fmt: skip
                else:
                    for di in (0, 1):
                        for dj in (0, 1):
                            below = placed.get((layer - 1, i + di, j + dj))
                            if below is None:
                                continue
                            k = [key for key, c in placed.items() if c is below][0]
                            other = f"s{list(placed).index(k)}"
                            normal = (centre - below) / np.linalg.norm(centre - below)
                            contacts.append(PointContact(
                                a=name, b=other, point=below + r * normal, normal=normal,
                                restitution=e, friction=mu, where=f"{name}/{other}"))  # fmt: skip
                count += 1
        layer += 1
    return ImpactProblem(bodies=bodies, contacts=contacts, title=f"A pile of {spheres} spheres")


def poured(spheres: int = 100, *, mu: float = 0.3, e: float = 0.2, seed: int = 1
           ) -> ImpactProblem:  # fmt: skip
    """``spheres`` equal spheres (0.1 kg, radius 0.05 m) poured into a box (fixed: a floor and
    walls), caught at the instant the last layer lands: square-packed layers of 5 x 5 in a
    corner of the box, each sphere resting on the one below it (a column) and touching its
    neighbours in the layer and the two walls of the corner where it is beside them (the box
    is wider than the pile: no row is wedged between two walls), all falling at about 1 m/s
    with random sideways velocities and spins (``seed``)."""
    rng = np.random.default_rng(seed)
    r, m, side = 0.05, 0.1, 5
    bodies: dict[str, RigidBody | FixedBody] = {"box": FixedBody(name="box")}
    contacts: list[PointContact] = []
    index: dict[tuple[int, int, int], str] = {}
    for k in range(spheres):
        layer, rest = divmod(k, side * side)
        i, j = divmod(rest, side)
        centre = np.array([(2 * i + 1) * r, (2 * j + 1) * r, (2 * layer + 1) * r])
        name = f"s{k}"
        index[layer, i, j] = name
        bodies[name] = RigidBody(name=name, mass=m, inertia_com=solid_sphere(m, r),
                                 position_com=centre,
                                 velocity_com=rng.normal(0.0, 0.2, 3) + [0, 0, -1.0 - 0.1 * layer],
                                 angular_velocity=rng.normal(0.0, 1.0, 3))  # fmt: skip

        def touch(other: str, normal: list[float], name: str = name,
                  centre: np.ndarray = centre) -> None:  # fmt: skip
            n = np.array(normal, dtype=float)
            contacts.append(PointContact(a=name, b=other, point=centre - r * n, normal=n,
                                         restitution=e, friction=mu,
                                         where=f"{name}/{other}"))  # fmt: skip

        touch(index[layer - 1, i, j] if layer else "box", [0, 0, 1])
        if i == 0:
            touch("box", [1, 0, 0])
        if j == 0:
            touch("box", [0, 1, 0])
        if i > 0:
            touch(index[layer, i - 1, j], [1, 0, 0])
        if j > 0:
            touch(index[layer, i, j - 1], [0, 1, 0])
    return ImpactProblem(bodies=bodies, contacts=contacts,
                         title=f"{spheres} spheres poured into a box")  # fmt: skip


def table(*, mu: float = 0.15, e: float = 0.0) -> ImpactProblem:
    """A table (12 kg top 1.2 x 0.8 m, 0.04 m thick, on four legs 0.7 m long: a rigid body
    whose centre of mass is 0.6 m up) landing at 1.5 m/s while sliding at 0.4 m/s on uneven
    ground: each foot on a patch of ground tilted its own way (normals up to 12 degrees from
    the vertical), all four touching at the instant."""
    mass = 12.0
    inertia = box_inertia(mass, (1.2, 0.8, 0.3))
    table_body = RigidBody(name="table", mass=mass, inertia_com=inertia,
                           position_com=[0.0, 0.0, 0.6], velocity_com=[0.4, 0.1, -1.5],
                           angular_velocity=[0.05, -0.1, 0.0])  # fmt: skip
    tilts = ((0.10, 0.05), (-0.15, 0.08), (0.05, -0.20), (-0.08, -0.12))  # (x, y) slopes
    contacts = []
    for k, ((sx, sy), (gx, gy)) in enumerate(zip(_CORNERS, tilts, strict=True)):
        normal = np.array([-gx, -gy, 1.0])
        contacts.append(PointContact(a="table", b="ground", point=[0.55 * sx, 0.35 * sy, 0.0],
                                     normal=normal / np.linalg.norm(normal), restitution=e,
                                     friction=mu, where=f"leg{k}"))  # fmt: skip
    return ImpactProblem(bodies={"table": table_body, "ground": FixedBody(name="ground")},
                         contacts=contacts, title="A table landing on uneven ground")  # fmt: skip

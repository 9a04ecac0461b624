"""Ground motion: the fixed bodies translate by a prescribed record, pulse or oscillation.

The record (CSV) gives times ``t_k`` (s, strictly increasing, ``t_0 >= 0``) and the ground's
acceleration ``a_k`` (m/s^2) along x (two columns) or along x, y, z (four columns); it is
linear between samples and zero before the first and after the last; the ground starts at
rest. Velocity and displacement are its exact integrals (piecewise quadratic and cubic):

    v_g(t) = V_k + a_k tau + s_k tau^2 / 2,  d_g(t) = D_k + V_k tau + a_k tau^2 / 2 + s_k tau^3 / 6

with ``tau = t - t_k`` and ``s_k`` the slope of the acceleration on interval ``k``.

carnot simulates in the ground's frame (the frame in which the fixed bodies do not move, so
that every impact is against a fixed obstacle, as :func:`carnot.solve_impact` models it): each
body feels the inertia force ``-m a_g(t)`` besides its weight, and the ground's work is that
force's work ``W = -int m a_g . v dt`` on the motion relative to the ground.

A one-cycle pulse (:class:`Pulse`, ``[simulation] ground_pulse``) is given by its formula
instead of samples: ``A sin(2 pi t / T)`` or ``A cos(2 pi t / T)`` on ``[0, T]``, zero
outside, with its velocity and displacement in closed form. (A sampled sine is linear between
samples: every sample is a kink that the contact phases' integrator must step through, and it
is only as exact as its sampling.)

A sustained oscillation (:class:`Oscillation`, ``[simulation] ground_oscillation``) moves the
fixed bodies by ``d_g(t) = A sin(w t + phase)`` along a unit direction for all time (``w = 2
pi f``): a vibrating table. Its velocity ``A w cos(w t + phase)`` is not zero at ``t = 0``, so
that there the ground's frame and the world's differ: positions and velocities, in the
scenario and in every result, are relative to the fixed bodies (their frame, whose origin is
the planes' mean position), as they are for a record or a pulse (which start at rest, where the
two frames meet).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from carnot.errors import InputError

#: Size limits of a record: rows and bytes.
MAX_ROWS = 1_000_000
MAX_BYTES = 64 * 1024 * 1024

_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(3)  # exact for cubics
#: Longest step (s) of the search for the next impact in flight under a record or a pulse.
SEARCH_STEP = 0.01
#: Steps per period of an oscillation: the longest step of a contact phase (as a pulse's
#: ``T/32``) and of the search for the next impact in flight.
STEPS_PER_PERIOD = 32


@dataclass(frozen=True, kw_only=True, eq=False)
class GroundMotion:
    """A piecewise-linear acceleration record ``times`` (N,) s, ``acceleration`` (N, 3) m/s^2.

    >>> g = GroundMotion.from_samples([0.0, 1.0], [[1.0, 0, 0], [1.0, 0, 0]])
    >>> g.velocity(2.0).tolist(), g.displacement(1.0).tolist()
    ([1.0, 0.0, 0.0], [0.5, 0.0, 0.0])
    """

    times: np.ndarray
    acceleration: np.ndarray
    slopes: np.ndarray
    velocity_nodes: np.ndarray
    displacement_nodes: np.ndarray

    @classmethod
    def from_samples(cls, times: object, acceleration: object, field: str = "ground_motion"
                     ) -> GroundMotion:  # fmt: skip
        t = np.asarray(times, dtype=float)
        a = np.asarray(acceleration, dtype=float)
        if t.ndim != 1 or len(t) < 2 or a.shape != (len(t), 3):
            raise InputError(field, "needs at least two rows of time and acceleration",
                             show_value=False)  # fmt: skip
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
            raise InputError(field, "every time and acceleration must be finite",
                             show_value=False)  # fmt: skip
        if t[0] < 0:
            raise InputError(f"{field} (row 1)", "the first time must be >= 0", float(t[0]))
        steps = np.diff(t)
        if np.any(steps <= 0):
            row = int(np.argmax(steps <= 0)) + 2
            raise InputError(f"{field} (row {row})", "times must increase strictly",
                             float(t[row - 1]))  # fmt: skip
        slopes = np.diff(a, axis=0) / steps[:, None]
        dv = a[:-1] * steps[:, None] + slopes * steps[:, None] ** 2 / 2
        v_nodes = np.vstack([np.zeros(3), np.cumsum(dv, axis=0)])
        dd = v_nodes[:-1] * steps[:, None] + a[:-1] * steps[:, None] ** 2 / 2 \
            + slopes * steps[:, None] ** 3 / 6
        d_nodes = np.vstack([np.zeros(3), np.cumsum(dd, axis=0)])
        return cls(times=t, acceleration=a, slopes=slopes, velocity_nodes=v_nodes,
                   displacement_nodes=d_nodes)  # fmt: skip

    @property
    def end(self) -> float:
        """The last sample's time (s): the acceleration is zero after it."""
        return float(self.times[-1])

    @property
    def max_step(self) -> float:
        """The longest step (s) of a contact phase before :attr:`end`: the shortest sample
        spacing (a short spike would be stepped over)."""
        return float(np.min(np.diff(self.times)))

    @property
    def search_step(self) -> float:
        """The longest step (s) between two samples of a gap in flight."""
        return SEARCH_STEP

    def _locate(self, t: float) -> tuple[int, float]:
        k = int(np.searchsorted(self.times, t, side="right")) - 1
        return k, t - self.times[max(k, 0)]

    def accel(self, t: float) -> np.ndarray:
        """The ground's acceleration (m/s^2, world) at time ``t`` (s)."""
        k, tau = self._locate(t)
        if k < 0 or t > self.times[-1]:
            return np.zeros(3)
        if k >= len(self.times) - 1:
            return self.acceleration[-1].copy()
        return self.acceleration[k] + self.slopes[k] * tau

    def velocity(self, t: float) -> np.ndarray:
        """The ground's velocity (m/s, world) at ``t``."""
        k, tau = self._locate(t)
        if k < 0:
            return np.zeros(3)
        if k >= len(self.times) - 1:
            return self.velocity_nodes[-1].copy()
        return self.velocity_nodes[k] + self.acceleration[k] * tau + self.slopes[k] * tau**2 / 2

    def displacement(self, t: float) -> np.ndarray:
        """The ground's displacement (m, world) from its start at ``t``."""
        k, tau = self._locate(t)
        if k < 0:
            return np.zeros(3)
        if k >= len(self.times) - 1:
            return self.displacement_nodes[-1] + self.velocity_nodes[-1] * tau
        return (self.displacement_nodes[k] + self.velocity_nodes[k] * tau
                + self.acceleration[k] * tau**2 / 2 + self.slopes[k] * tau**3 / 6)  # fmt: skip

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        """The record's sample times strictly inside ``(t0, t1)``, with the ends."""
        inner = self.times[(self.times > t0) & (self.times < t1)]
        return [t0, *inner.tolist(), t1]

    def kinks(self, t0: float, t1: float) -> list[float]:
        """Where the acceleration is not smooth in ``[t0, t1]``: its samples (with the ends)."""
        return self.breakpoints(t0, t1)

    def work_in_flight(self, mass: float, t0: float, t1: float, velocity0: np.ndarray,
                       gravity: np.ndarray) -> float:  # fmt: skip
        """The work (J) of the inertia force ``-m a_g`` on a body in free flight from ``t0``
        with relative velocity ``velocity0`` (m/s) under ``gravity`` (m/s^2), to ``t1``:
        ``v(t) = v0 + g (t - t0) - (v_g(t) - v_g(t0))``. Exact (Gauss-Legendre, 3 nodes on
        each piece of the record, where the integrand is a cubic)."""
        vg0 = self.velocity(t0)
        total = 0.0
        edges = self.breakpoints(t0, t1)
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            half = (hi - lo) / 2
            for x, w in zip(_GAUSS_NODES, _GAUSS_WEIGHTS, strict=True):
                t = lo + half * (x + 1)
                v = velocity0 + gravity * (t - t0) - (self.velocity(t) - vg0)
                total += w * half * float(self.accel(t) @ v)
        return -mass * total


@dataclass(frozen=True, kw_only=True, eq=False)
class Pulse:
    """One cycle of ``a_g(t) = A f(2 pi t / T) d`` on ``0 <= t <= T`` (``f`` = sin for
    ``shape = "sine"``, cos for ``"cosine"``; ``d`` a unit direction), zero outside: the
    cycloidal pulses of types A and B of N. Makris and Y. Roussos, Geotechnique 50 (2000)
    243-262, and J. Zhang and N. Makris, J. Eng. Mech. 127 (2001) 473-483. Closed forms, with
    ``w = 2 pi / T``: sine ``v_g = A (1 - cos w t)/w``, ``d_g = A (t - sin(w t)/w)/w``; cosine
    ``v_g = A sin(w t)/w``, ``d_g = A (1 - cos w t)/w^2``; after ``T`` the ground goes on at
    ``v_g(T)`` (zero: one whole cycle; a sine pulse leaves it displaced by ``A T^2 / 2 pi``).

    >>> p = Pulse(shape="sine", amplitude=2.0, period=0.4, direction=np.array([1.0, 0, 0]))
    >>> float(p.accel(0.1)[0]), float(p.velocity(0.4)[0]), round(float(p.displacement(1.0)[0]), 12)
    (2.0, 0.0, 0.050929581789)
    """

    shape: str
    amplitude: float
    period: float
    direction: np.ndarray

    @property
    def times(self) -> np.ndarray:
        """Breakpoints every ``T/32`` (s): the end is ``times[-1]`` (:attr:`end`), and no step
        of a contact phase spans more than ``T/32`` (the step bound a record's samples give),
        so that a lift-off while the pulse exceeds ``g tan alpha`` for a short while is not
        stepped over (within 1 % of the threshold: a window of 0.045 T)."""
        return np.linspace(0.0, self.period, 33)

    @property
    def end(self) -> float:
        """``T`` (s): the acceleration is zero after it."""
        return self.period

    @property
    def max_step(self) -> float:
        """``T/32`` (s): see :attr:`times`."""
        return self.period / STEPS_PER_PERIOD

    @property
    def search_step(self) -> float:
        """The longest step (s) between two samples of a gap in flight."""
        return SEARCH_STEP

    def kinks(self, t0: float, t1: float) -> list[float]:
        """Where the acceleration is not smooth in ``[t0, t1]``: its start and end (with the
        ends)."""
        inner = [t for t in (0.0, self.period) if t0 < t < t1]
        return [t0, *inner, t1]

    def _scalars(self, t: float) -> tuple[float, float, float]:
        """(a, v, d) along the direction at ``t`` (m/s^2, m/s, m)."""
        big_t, amp = self.period, self.amplitude
        w = 2 * np.pi / big_t
        if t <= 0:
            return 0.0, 0.0, 0.0
        tau = min(t, big_t)
        if self.shape == "sine":
            a, v = amp * np.sin(w * tau), amp * (1 - np.cos(w * tau)) / w
            d = amp * (tau - np.sin(w * tau) / w) / w
        else:
            a, v, d = amp * np.cos(w * tau), amp * np.sin(w * tau) / w, \
                amp * (1 - np.cos(w * tau)) / w**2  # fmt: skip
        if t > big_t:
            return 0.0, float(v), float(d + v * (t - big_t))
        return float(a), float(v), float(d)

    def accel(self, t: float) -> np.ndarray:
        """The ground's acceleration (m/s^2, world) at ``t`` (s)."""
        return self._scalars(t)[0] * self.direction

    def velocity(self, t: float) -> np.ndarray:
        """The ground's velocity (m/s, world) at ``t``."""
        return self._scalars(t)[1] * self.direction

    def displacement(self, t: float) -> np.ndarray:
        """The ground's displacement (m, world) from its start at ``t``."""
        return self._scalars(t)[2] * self.direction

    def work_in_flight(self, mass: float, t0: float, t1: float, velocity0: np.ndarray,
                       gravity: np.ndarray) -> float:  # fmt: skip
        """The work (J) of ``-m a_g`` on a body in free flight (as
        :meth:`GroundMotion.work_in_flight`), in closed form: with ``v = v0 + g (t - t0) -
        (v_g - v_g0)``, ``int a_g . v dt = (v0 + v_g0) . dv_g + g . (v_g1 (t1 - t0) - dd_g)
        - (|v_g1|^2 - |v_g0|^2) / 2``."""
        return _closed_form_work(self, mass, t0, t1, velocity0, gravity)


@dataclass(frozen=True, kw_only=True, eq=False)
class Oscillation:
    """Sustained harmonic motion of the fixed bodies (a vibrating table): with ``w = 2 pi f``
    (``f`` the ``frequency``, Hz), ``A`` the ``amplitude`` (m), ``phi`` the ``phase`` (rad) and
    ``d`` a unit direction, for all ``t``

        d_g(t) = A sin(w t + phi) d,  v_g(t) = A w cos(w t + phi) d,
        a_g(t) = -A w^2 sin(w t + phi) d

    (displacement from the mean position, m; velocity, m/s; acceleration, m/s^2; world axes).
    Smooth everywhere: no kinks, and it never ends (a body on it never comes to rest).

    >>> table = Oscillation(amplitude=0.01, frequency=5.0, direction=np.array([0, 1.0, 0]))
    >>> round(float(table.displacement(0.05)[1]), 15), round(float(table.accel(0.05)[1]), 9)
    (0.01, -9.869604401)
    >>> round(float(table.velocity(0.0)[1]), 12), table.period
    (0.314159265359, 0.2)
    """

    amplitude: float
    frequency: float
    direction: np.ndarray
    phase: float = 0.0

    @property
    def angular_frequency(self) -> float:
        """``w = 2 pi f`` (rad/s)."""
        return 2 * math.pi * self.frequency

    @property
    def period(self) -> float:
        """``1 / f`` (s)."""
        return 1.0 / self.frequency

    @property
    def end(self) -> float:
        """Never (s): the motion is sustained."""
        return math.inf

    @property
    def max_step(self) -> float:
        """``T/32`` (s), the longest step of a contact phase: a lift-off where the table's
        downward acceleration first exceeds the gravity across its surface is not stepped
        over (as for a pulse)."""
        return self.period / STEPS_PER_PERIOD

    @property
    def search_step(self) -> float:
        """The longest step (s) between two samples of a gap in flight: the smaller of a
        record's and ``T/32`` (the gap is a quadratic plus a sinusoid of period ``T``)."""
        return min(SEARCH_STEP, self.period / STEPS_PER_PERIOD)

    def kinks(self, t0: float, t1: float) -> list[float]:
        """Where the acceleration is not smooth in ``[t0, t1]``: nowhere (the ends only)."""
        return [t0, t1]

    def _angle(self, t: float) -> float:
        return self.angular_frequency * t + self.phase

    def accel(self, t: float) -> np.ndarray:
        """The ground's acceleration (m/s^2, world) at ``t`` (s)."""
        w = self.angular_frequency
        return -self.amplitude * w * w * math.sin(self._angle(t)) * self.direction

    def velocity(self, t: float) -> np.ndarray:
        """The ground's velocity (m/s, world) at ``t``."""
        return self.amplitude * self.angular_frequency * math.cos(self._angle(t)) \
            * self.direction  # fmt: skip

    def displacement(self, t: float) -> np.ndarray:
        """The ground's displacement (m, world) from its mean position at ``t``."""
        return self.amplitude * math.sin(self._angle(t)) * self.direction

    def work_in_flight(self, mass: float, t0: float, t1: float, velocity0: np.ndarray,
                       gravity: np.ndarray) -> float:  # fmt: skip
        """The work (J) of ``-m a_g`` on a body in free flight, in closed form (as
        :meth:`Pulse.work_in_flight`)."""
        return _closed_form_work(self, mass, t0, t1, velocity0, gravity)


def _closed_form_work(ground: Pulse | Oscillation, mass: float, t0: float, t1: float,
                      velocity0: np.ndarray, gravity: np.ndarray) -> float:  # fmt: skip
    """``-m int_t0^t1 a_g . v dt`` (J) for a flight ``v = v0 + g (t - t0) - (v_g - v_g0)``
    relative to a ground whose velocity and displacement are known in closed form: by parts,
    ``int a_g . v dt = (v0 + v_g0) . dv_g + g . (v_g1 (t1 - t0) - dd_g) - (|v_g1|^2 -
    |v_g0|^2) / 2``."""
    vg0, vg1 = ground.velocity(t0), ground.velocity(t1)
    dd = ground.displacement(t1) - ground.displacement(t0)
    total = float((velocity0 + vg0) @ (vg1 - vg0)) + float(
        gravity @ (vg1 * (t1 - t0) - dd)) - 0.5 * float(vg1 @ vg1 - vg0 @ vg0)  # fmt: skip
    return -mass * total


#: What the simulation's ground can be: a sampled record, a pulse's formula or a sustained
#: oscillation's.
Ground = GroundMotion | Pulse | Oscillation


def read_record(path: Path, field: str) -> GroundMotion:
    """Read a ground-motion CSV: rows ``t, a_x`` or ``t, a_x, a_y, a_z`` (a header line and
    ``#`` comments allowed), within :data:`MAX_ROWS` and :data:`MAX_BYTES`."""
    try:
        size = path.stat().st_size
    except OSError as err:
        raise InputError(field, f"cannot read {path} ({err.strerror})", show_value=False) from None
    if size > MAX_BYTES:
        raise InputError(field, f"the record must be at most {MAX_BYTES} bytes", size)
    rows: list[list[float]] = []
    header = False
    with path.open(encoding="utf-8") as handle:
        for number, line in enumerate(handle, start=1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            cells = [c.strip() for c in text.split(",")]
            try:
                values = [float(c) for c in cells]
            except ValueError:
                if not rows and not header:
                    header = True
                    continue  # one header line before the data
                raise InputError(f"{field} (line {number})", "must be numbers", text) from None
            if len(values) not in (2, 4):
                raise InputError(f"{field} (line {number})",
                                 "must have 2 columns (t, a_x) or 4 (t, a_x, a_y, a_z)", text)
            if rows and len(values) != len(rows[0]):
                raise InputError(f"{field} (line {number})",
                                 "must have as many columns as the first row", text)
            rows.append(values)
            if len(rows) > MAX_ROWS:
                raise InputError(field, f"the record must have at most {MAX_ROWS} rows",
                                 len(rows))  # fmt: skip
    if len(rows) < 2:
        raise InputError(field, "needs at least two rows of time and acceleration", len(rows))
    data = np.array(rows)
    accel = np.zeros((len(data), 3))
    accel[:, : data.shape[1] - 1] = data[:, 1:]
    return GroundMotion.from_samples(data[:, 0], accel, field)

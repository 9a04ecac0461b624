"""Audits of whole rollouts: one MuJoCo runs here (:func:`audit_model`), or one recorded by
the user and replayed state by state (:func:`audit_recording`).

A recording is an ``.npz`` file (NumPy's zip of arrays, read with ``allow_pickle=False``)
with ``qpos`` (N x nq) and ``qvel`` (N x nv): the states at the start of N - 1 steps and the
last one; optionally ``time`` (N), ``ctrl`` (N x nu), ``act`` (N x na) and
``qacc_warmstart`` (N x nv: ``data.qacc_warmstart`` before each step, so that MuJoCo's
iterative constraint solver repeats its answers exactly). Contacts are found again by
MuJoCo from the model and each state; the per-step ``residual`` then shows how far the
recorded velocities are from MuJoCo's step from the recorded state.
"""

from __future__ import annotations

import dataclasses
import math
import os
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.model.mjcf import keyframe_id, load_mujoco
from carnot.rollout.audit import AuditReport, EnergyAudit, RigidSettings

#: The largest recording read (bytes) and the most steps audited.
MAX_RECORDING_BYTES = 512 * 1024 * 1024
MAX_STEPS = 2_000_000

_OPTIONAL = ("time", "ctrl", "act", "qacc_warmstart")


def load_model(path: str | Path) -> Any:
    """The ``MjModel`` of an MJCF file (an ``InputError`` naming the file if it cannot be
    read)."""
    mujoco = load_mujoco()
    source = str(path)
    try:
        return mujoco.MjModel.from_xml_path(source)
    except (ValueError, OSError) as err:
        message = " ".join(str(err).split())[:300]
        raise InputError(
            source, f"cannot read the MJCF model ({message})", show_value=False
        ) from None


def audit_model(
    path: str | Path,
    *,
    keyframe: str | int | None = None,
    duration: float = 1.0,
    rigid: RigidSettings | None = None,
    min_speed: float | None = None,
    qpos: Sequence[float] | None = None,
    qvel: Sequence[float] | None = None,
) -> AuditReport:
    """Run the MJCF model at ``path`` from ``keyframe`` (or its default state), then
    ``qpos``/``qvel`` where given (model.nq and model.nv numbers), for ``duration`` (s) with
    its own integrator and timestep, and audit every step.

    >>> report = audit_model("examples/audit/ball_drop.xml", keyframe="drop", duration=0.6)
    >>> [(e.pair, round(e.start, 3), round(e.effective_restitution, 3)) for e in report.episodes]
    [(('floor', 'ball'), 0.452, 0.252)]
    """
    mujoco = load_mujoco()
    model = load_model(path)
    if not (math.isfinite(duration) and duration > 0):
        raise InputError("duration", "must be a finite number of seconds > 0", duration)
    steps = round(duration / model.opt.timestep)
    if steps > MAX_STEPS:
        raise InputError(
            "duration", f"asks for {steps} steps of {model.opt.timestep:g} s (at most "
            f"{MAX_STEPS})", duration,
        )  # fmt: skip
    data = mujoco.MjData(model)
    if keyframe is not None:
        mujoco.mj_resetDataKeyframe(model, data, keyframe_id(mujoco, model, keyframe, str(path)))
    for name, value, size in (("qpos", qpos, model.nq), ("qvel", qvel, model.nv)):
        if value is not None:
            getattr(data, name)[:] = _state_numbers(name, value, size)
    title = Path(path).name + (f" from keyframe {keyframe}" if keyframe is not None else "")
    audit = EnergyAudit(model, data, rigid=rigid, min_speed=min_speed, title=title)
    for _ in range(max(steps, 1)):
        audit.step()
    return audit.finish()


def _state_numbers(name: str, value: Sequence[float], size: int) -> np.ndarray:
    """``value`` as ``size`` finite numbers (an ``InputError`` naming ``name`` otherwise)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, f"must be {size} numbers", value) from None
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        raise InputError(name, f"must be {size} finite numbers (the model's size); "
                         f"{arr.size} numbers", np.ravel(arr).tolist())  # fmt: skip
    return arr


def replay_warnings(model: Any, names: Sequence[str]) -> tuple[str, ...]:
    """What a recording holding the arrays ``names`` lacks for ``model`` (sentences): the
    controls of a model with actuators, the activations of one with activation states.
    Without them MuJoCo's step from the recorded state runs with zero controls, so the
    recorded velocities are not its step's: the per-step residual holds the actuators' work
    (1.64 J a step on a PD-controlled robot).

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string('<mujoco><worldbody><body><joint name="j"/>'
    ...     '<geom size=".1"/></body></worldbody><actuator><motor joint="j"/></actuator></mujoco>')
    >>> replay_warnings(model, ["qpos", "qvel"])  # doctest: +ELLIPSIS
    ('the recording has no ctrl but the model has 1 actuator(s): ...',)
    """
    out = []
    for name, count, what in (("ctrl", model.nu, "actuator(s)"),
                              ("act", model.na, "activation state(s)")):  # fmt: skip
        if count and name not in names:
            out.append(
                f"the recording has no {name} but the model has {count} {what}: MuJoCo "
                f"replays each step with {name} = 0, so the per-step residual includes what "
                f"the recorded {name} did (record data.{name} before each step)"
            )
    return tuple(out)


def load_recording(path: str | Path, model: Any) -> dict[str, np.ndarray]:
    """The arrays of a recording (module docstring), checked against ``model``."""
    source = str(path)
    size = os.path.getsize(source)
    if size > MAX_RECORDING_BYTES:
        raise InputError(source, f"is {size} bytes (at most {MAX_RECORDING_BYTES})",
                         show_value=False)  # fmt: skip
    try:
        with np.load(source, allow_pickle=False) as archive:
            names = list(archive.files)
            unknown = sorted(set(names) - {"qpos", "qvel", *_OPTIONAL})
            if unknown:
                raise InputError(
                    f"{source}: {unknown[0]}",
                    f"is not a recording array (known: qpos, qvel, {', '.join(_OPTIONAL)})",
                    show_value=False,
                )  # fmt: skip
            arrays = {name: archive[name] for name in names}
    except (ValueError, OSError, zipfile.BadZipFile, EOFError) as err:
        message = " ".join(str(err).split())[:200]
        raise InputError(source, f"is not a readable .npz recording ({message})",
                         show_value=False) from None  # fmt: skip
    for name in ("qpos", "qvel"):
        if name not in arrays:
            raise InputError(f"{source}: {name}", "is missing (a recording needs qpos and qvel)",
                             show_value=False)  # fmt: skip
    count = arrays["qpos"].shape[0] if arrays["qpos"].ndim else 0
    if not 2 <= count <= MAX_STEPS + 1:
        raise InputError(f"{source}: qpos", f"must hold 2 to {MAX_STEPS + 1} states",
                         count)  # fmt: skip
    widths = {"qpos": model.nq, "qvel": model.nv, "ctrl": model.nu, "act": model.na,
              "qacc_warmstart": model.nv, "time": None}  # fmt: skip
    out = {}
    for name, array in arrays.items():
        shape = (count,) if widths[name] is None else (count, widths[name])
        if array.dtype.kind not in "fiu" or array.shape != shape:
            raise InputError(
                f"{source}: {name}", f"must be {' x '.join(map(str, shape))} numbers (the "
                "model's size, one row per state)",
                f"{array.dtype} array of shape {array.shape}",
            )  # fmt: skip
        values = np.asarray(array, dtype=float)
        if not np.all(np.isfinite(values)):
            raise InputError(f"{source}: {name}", "must be finite numbers", show_value=False)
        out[name] = values
    if "time" in out:
        steps = np.diff(out["time"])
        if not np.allclose(steps, model.opt.timestep, rtol=1e-9, atol=0):
            raise InputError(
                f"{source}: time", "must advance by the model's timestep "
                f"({model.opt.timestep:g} s) from state to state", float(steps.min()),
            )  # fmt: skip
    return out


def audit_recording(
    path: str | Path,
    recording: str | Path,
    *,
    rigid: RigidSettings | None = None,
    min_speed: float | None = None,
) -> AuditReport:
    """Audit a recorded rollout of the MJCF model at ``path`` (module docstring): MuJoCo's
    forward quantities at each recorded state, the recorded velocity after the step."""
    mujoco = load_mujoco()
    model = load_model(path)
    arrays = load_recording(recording, model)
    qpos, qvel = arrays["qpos"], arrays["qvel"]
    times = arrays.get("time", np.arange(qpos.shape[0]) * model.opt.timestep)
    data = mujoco.MjData(model)
    scratch = mujoco.MjData(model)

    def load_state(target: Any, k: int) -> None:
        target.qpos[:], target.qvel[:], target.time = qpos[k], qvel[k], times[k]
        for name in ("ctrl", "act", "qacc_warmstart"):
            if name in arrays:
                getattr(target, name)[:] = arrays[name][k]

    load_state(data, 0)
    title = f"{Path(path).name}, recording {Path(recording).name}"
    audit = EnergyAudit(model, data, rigid=rigid, min_speed=min_speed, title=title)
    for k in range(qpos.shape[0] - 1):
        load_state(scratch, k)
        if audit.exact:  # mj_step: the forward quantities and qDeriv of the step's start
            mujoco.mj_step(model, scratch)
        else:
            mujoco.mj_forward(model, scratch)
        audit.record(scratch, times[k], qpos[k], qvel[k], qpos[k + 1], qvel[k + 1])
    load_state(data, qpos.shape[0] - 1)  # the last state's controls for its energy
    report = audit.finish()
    return dataclasses.replace(report, warnings=replay_warnings(model, list(arrays)))

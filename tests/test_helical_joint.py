"""A joint type added from outside the package: a helical (screw) joint, defined and registered
in this module alone, runs through every algorithm and file with no change to the package.

The case: a nut of mass ``m`` and moment of inertia ``I`` about its axis turns on a vertical
screw of pitch ``p`` (m/rad) fixed to the ground, its centre of mass on the axis, gravity ``g``
down. Its height is ``z = z0 + p theta``. The joint's wrench on the nut (parent on child, about
the joint origin on the axis) has the axial force ``F = m (p theta_dd + g)`` (Newton along z)
and the axial moment ``T = I theta_dd`` (Euler about z: the angular velocity is along a
principal axis, so no gyroscopic term). The effort along the joint's coordinate is the twist
``(p a, a)`` dotted with that wrench:

    tau = p F + T = (I + m p^2) theta_dd + m g p,

the torque the parent (a motor on the screw) exerts on the nut; with no driver the nut runs
down at ``theta_dd = -m g p / (I + m p^2)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import hexapod as hx
from hexapod.output.actuation import driver_statistics
from hexapod.output.inverse_csv import inverse_column_units
from hexapod.scene.element import check_finite
from hexapod.scene.joints import Cylindrical, register, unregister
from hexapod.scene.joints.base import AXIS, NUMBER
from hexapod.scene.joints.geometry import (
    ANGLE,
    LENGTH,
    angle_rate,
    axial_displacement,
    wrapped_angle,
)


@dataclass(eq=False)
class Helical(Cylindrical):
    """A screw: the axes aligned and the child frame's origin on the parent's axis (the rows of
    a cylindrical joint), and ``a_p . d = pitch theta`` with ``theta`` the angle about the axis
    as a revolute joint measures it. ``pitch`` in L/rad; the coordinate is the angle."""

    pitch: float = 0.0
    kind = "helical"
    drivable = True
    default_axis = {3: (0.0, 0.0, 1.0)}
    exists_in_plane = False
    plane_hint = "a revolute or prismatic joint"
    particle_ends = {}
    coordinate_unit, effort_unit = ANGLE, "N m"

    def problems(self):
        out = super().problems()
        if check_finite(self, "pitch", self.pitch, out) and self.pitch == 0:
            out.append(self.problem("pitch", "must not be zero (that is a revolute joint)"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.pitch = self.pitch * length
        return out

    @classmethod
    def file_keys(cls, dimension):
        return {"axis": AXIS, "pitch": (NUMBER, True)}

    def rows(self, g, laws):
        # p (theta - s / p), wrapped as a revolute driver is: zero when the slide is p theta,
        # whatever the number of turns
        screw = self.pitch * wrapped_angle(g, axial_displacement(g) / self.pitch)
        return super().rows(g, laws) + [("screw", screw, LENGTH)]

    def driver_row(self, g, f):
        return wrapped_angle(g, f)

    def rate(self, g, q, qdot):
        return angle_rate(g)

    def twist(self, dimension):
        a = self.unit_axis(dimension)
        return self.pitch * a, a

    def tree_step(self, value):
        import casadi as ca

        a = ca.DM(self.unit_axis(3))
        half = value / 2
        return ca.vertcat(ca.cos(half), ca.sin(half) * a), value * self.pitch * a


@pytest.fixture(autouse=True, scope="module")
def helical_registered():
    """The type exists while this module's tests run, and not in the others'."""
    register(Helical)
    yield
    unregister("helical")


M, I_AXIS, PITCH, Z0, G = 2.0, 0.05, 0.1, 0.3, 9.81
LAW = dict(offset=0.2, sin=[0.8], cos=[0.3], frequency=0.7)  # theta(t), rad


def theta_of(t):
    return (x for x in hx.scene.Harmonic(**LAW).evaluate(np.asarray(t, dtype=float)))


def closed_form_effort(theta_dd):
    return (I_AXIS + M * PITCH**2) * theta_dd + M * G * PITCH


def screw_scene(driven: bool = True) -> hx.Scene:
    scene = hx.Scene("screw")
    scene.add(hx.scene.SpatialBody("nut", M, [0.03, 0.03, I_AXIS], position=[0.0, 0.0, Z0]))
    scene.add(Helical("screw", "ground", "nut", axis=[0.0, 0.0, 1.0], pitch=PITCH))
    if driven:
        scene.add(hx.scene.JointDriver("drive", "screw", hx.scene.Harmonic(**LAW)))
    return scene


SCENE_FILE = """\
[scene]
name = "screw"
length_unit = "cm"

[[body]]
name = "nut"
mass = 2.0
inertia = [300.0, 300.0, 500.0]  # kg cm^2
position = [0, 0, 30]

[[joint]]
name = "screw"
type = "helical"
parent = "ground"
child = "nut"
axis = [0, 0, 1]
pitch = 10.0  # cm/rad

[[driver]]
name = "drive"
joint = "screw"
law = { type = "harmonic", offset = 0.2, sin = [0.8], cos = [0.3], frequency = 0.7 }
"""


def nut_angle(q):
    """The nut's rotation about z from its Euler parameters (scalar first)."""
    e0, e3 = q[..., 3], q[..., 6]
    return 2 * np.arctan2(e3, e0)


def test_the_type_is_registered_and_asked():
    assert hx.scene.joints.JOINT_TYPES["helical"] is Helical
    model = hx.assemble(screw_scene())
    joint = model.joints[0]
    assert joint.kind == "helical" and isinstance(joint.type, Helical)
    assert joint.type.pitch == PITCH
    assert [r.name for r in model.rows] == [f"screw/{n}" for n in
                                            ("ax1", "ax2", "t1", "t2", "screw")] + ["drive"]
    assert [r.kind for r in model.rows][-2:] == ["length", "angle"]


def test_kinematics_the_height_follows_pitch_times_angle():
    model = hx.assemble(screw_scene())
    data = model.create_data()
    for t in np.linspace(0.0, 1.5, 7):
        q, v = hx.consistent_state(model, data, t)
        theta, theta_d, _ = theta_of(t)
        assert nut_angle(q) == pytest.approx(theta, abs=1e-12)
        assert np.allclose(q[:3], [0.0, 0.0, Z0 + PITCH * theta], rtol=0, atol=1e-12)
        assert np.allclose(v[:3], [0.0, 0.0, PITCH * theta_d], rtol=0, atol=1e-12)
        assert np.allclose(v[3:6], [0.0, 0.0, theta_d], rtol=0, atol=1e-12)


def test_forward_dynamics_effort_and_wrench_equal_the_closed_form():
    model = hx.assemble(screw_scene())
    for t in np.linspace(0.0, 1.5, 7):
        data = model.create_data()
        q, v = hx.consistent_state(model, data, t)
        hx.forward_dynamics(model, data, t, q, v)
        _, _, theta_dd = theta_of(t)
        tau = closed_form_effort(theta_dd)
        wrenches = hx.joint_wrenches(model, data)
        assert wrenches.effort[0] == pytest.approx(tau, rel=1e-10)
        # the effort exerted by the parent on the child is minus the driver's multiplier
        assert hx.driver_efforts(model, data)["drive"] == pytest.approx(tau, rel=1e-10)
        # the joint wrench's axial components, and nothing across the axis
        force, torque = wrenches.force[0], wrenches.torque[0]
        assert force[2] == pytest.approx(M * (PITCH * theta_dd + G), rel=1e-10)
        assert torque[2] == pytest.approx(I_AXIS * theta_dd, rel=1e-9, abs=1e-10)
        assert np.allclose(force[:2], 0.0, atol=1e-10) and np.allclose(torque[:2], 0.0,
                                                                      atol=1e-10)


@pytest.mark.parametrize("method", ["tree", "phase", "saddle"])
def test_inverse_dynamics_every_path(method):
    model = hx.assemble(screw_scene())
    times = np.linspace(0.0, 1.4, 15)
    result = hx.inverse_dynamics(model, times, method=method)
    assert result.method == method
    _, _, theta_dd = theta_of(times)
    assert np.allclose(result.effort[:, 0], closed_form_effort(theta_dd), rtol=1e-10,
                       atol=1e-10)
    assert np.allclose(result.force[:, 0, 2], M * (PITCH * theta_dd + G), rtol=1e-10)
    assert np.allclose(result.torque[:, 0, 2], I_AXIS * theta_dd, rtol=0, atol=1e-10)
    assert np.allclose(result.q[:, 2], Z0 + PITCH * next(theta_of(times)), rtol=0, atol=1e-12)


def test_the_tree_path_takes_it_by_default():
    model = hx.assemble(screw_scene())
    assert hx.inverse_dynamics(model, np.linspace(0.0, 1.0, 5)).method == "tree"


def test_report_columns_and_units():
    model = hx.assemble(screw_scene())
    units = inverse_column_units(model)
    assert list(units)[:2] == ["t", "tau:screw"]
    assert units["tau:screw"][0] == "N m"
    times = np.linspace(0.0, 1.0 / 0.7, 41)
    result = hx.inverse_dynamics(model, times)
    table = hx.output.inverse_table(model, result)
    assert table.shape == (times.size, len(hx.output.inverse_columns(model)))
    assert np.allclose(table[:, 1], result.effort[:, 0], rtol=0, atol=0)
    (stats,) = driver_statistics(model, result)
    assert stats.joint == "screw" and stats.unit == "N m"


def test_forward_simulation_runs_down_the_screw_as_the_closed_form():
    model = hx.assemble(screw_scene(driven=False))
    assert model.energy_conserved
    run = hx.simulate(model, 0.6, rtol=1e-10, atol=1e-12)
    assert run.status == "finished", run.message
    alpha = -M * G * PITCH / (I_AXIS + M * PITCH**2)
    theta = 0.5 * alpha * run.t**2
    assert np.allclose(nut_angle(run.q), theta, rtol=0, atol=1e-7)
    assert np.allclose(run.q[:, 2], Z0 + PITCH * theta, rtol=0, atol=1e-8)
    assert run.energy_drift is not None and abs(run.energy_drift) < 1e-8


def test_from_a_scene_file_in_centimetres(tmp_path):
    path = tmp_path / "screw.toml"
    path.write_text(SCENE_FILE)
    scene = hx.read_scene(path)
    assert isinstance(scene.joints["screw"], Helical) and scene.joints["screw"].pitch == 10.0
    times = np.linspace(0.0, 1.4, 15)
    from_file = hx.inverse_dynamics(hx.assemble(scene), times)
    in_python = hx.inverse_dynamics(hx.assemble(screw_scene()), times)
    assert np.allclose(from_file.effort, in_python.effort, rtol=1e-12, atol=1e-12)
    assert np.allclose(from_file.q, in_python.q, rtol=0, atol=1e-12)
    # written back with its pitch (the type's file keys), read back the same
    again = tmp_path / "again.toml"
    hx.write_scene(scene, again)
    assert "pitch = 10.0" in again.read_text()
    assert hx.read_scene(again).joints["screw"].pitch == 10.0


def test_bad_files_name_the_type_and_key(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE_FILE.replace("pitch = 10.0  # cm/rad\n", "").replace(
        'name = "drive"', 'name = "drive"\n# no pitch above'))
    with pytest.raises(hx.ModelError) as missing:
        hx.read_scene(path)
    assert "joint[0].pitch" in str(missing.value) and "missing required key 'pitch'" in str(
        missing.value)
    plane = hx.Scene("flat", 2)
    plane.add(hx.scene.PlanarBody("nut", 1.0, 0.1))
    plane.add(Helical("screw", "ground", "nut", pitch=0.1))
    with pytest.raises(hx.ModelError, match="no helical joint in the plane: use a revolute"):
        plane.validate()

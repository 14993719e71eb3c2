"""The GGL equations of :class:`~hexapod.simulation.integrators.radau.RadauIIA5GGL` as CasADi
Functions, in local Lie-group coordinates of a step.

The residual ``F(t, y)`` of the stabilised index-2 equations of Gear, Gupta and Leimkuhler
(see :mod:`hexapod.simulation.integrators.radau`) with ``y = (xi, v, lambda, mu)`` and the
positions ``q = q_n (+) xi`` (translations added, rotations composed in the body frame,
``p <- p * exp(xi'/2)``); a rotation vector's rate is ``J_r(xi)^-1 omega``
(:func:`dexp_inverse_sx`). Built once per model, with the exact Jacobian of ``F``.
"""

from __future__ import annotations

import casadi as ca

from hexapod.model.model import Model
from hexapod.spatial import quaternion_product


def _cross(a, b):
    """Cross product of two SX 3-vectors."""
    return ca.vertcat(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                      a[0] * b[1] - a[1] * b[0])


def _exp_sx(x):
    """Unit quaternion of the rotation vector ``x`` (SX), smooth through ``x = 0``: below
    1e-3 rad the series of ``cos(theta/2)`` and ``sin(theta/2)/theta`` (truncation below
    1e-22), and a square root that never sees zero, so that derivatives stay finite."""
    theta2 = ca.dot(x, x)
    small = theta2 < 1e-6
    theta = ca.sqrt(ca.if_else(small, 1.0, theta2))
    c = ca.if_else(small, 1 - theta2 / 8 + theta2**2 / 384, ca.cos(theta / 2))
    s = ca.if_else(small, 0.5 - theta2 / 48 + theta2**2 / 3840, ca.sin(theta / 2) / theta)
    return ca.vertcat(c, s * x)


def dexp_inverse_sx(x, u):
    """``J_r(x)^-1 u`` (SX 3-vectors): the rate of the rotation vector ``x`` of ``R_n Exp(x)``
    when the body turns at ``u`` (body frame). The inverse right Jacobian of SO(3),
    ``I + [x]/2 + (1/theta^2 - (1 + cos theta) / (2 theta sin theta)) [x]^2``, with its series
    ``1/12 + theta^2/720`` below 1e-3 rad (truncation ``theta^4 / 30240``)."""
    theta2 = ca.dot(x, x)
    small = theta2 < 1e-6
    theta = ca.sqrt(ca.if_else(small, 1.0, theta2))
    c = ca.if_else(small, 1.0 / 12 + theta2 / 720,
                   1 / theta**2 - (1 + ca.cos(theta)) / (2 * theta * ca.sin(theta)))
    xu = _cross(x, u)
    return u + 0.5 * xu + c * _cross(x, xu)


def ggl_functions(model: Model) -> dict:
    """CasADi Functions built once per model (:meth:`Model.built_once`): the residual ``F`` of
    the GGL equations in the local coordinates ``xi`` of the step, ``q = q_n (+) xi``, at one
    point and at three stages, and at ``xi = 0`` with its Jacobian in ``(xi, v, lambda, mu)``
    (exact: the Lie-group composition and ``J_r^-1`` are part of the expression)."""
    return model.built_once(("radau5-ggl",), _ggl_functions)


def _ggl_functions(model: Model) -> dict:
    q0 = ca.SX.sym("q0", model.n_q)
    xi = ca.SX.sym("xi", model.n_v)
    v = ca.SX.sym("v", model.n_v)
    lam = ca.SX.sym("lam", model.n_c)
    mu = ca.SX.sym("mu", model.n_c)
    w = ca.SX.sym("w", model.n_w)
    wd = ca.SX.sym("wd", model.n_w)
    parts, rotations = [], []
    for b in model.bodies:
        qb, xb = q0[b.q.start:b.q.stop], xi[b.v.start:b.v.stop]
        if b.kind == "spatial":
            parts += [qb[:3] + xb[:3], quaternion_product(qb[3:], _exp_sx(xb[3:]))]
            rotations.append(b.v.start + 3)
        else:
            parts.append(qb + xb)
    q = ca.vertcat(*parts)
    symbols = {"q": q, "v": v, "w": w, "wd": wd}

    def call(function: ca.Function) -> ca.SX:
        return function(*[symbols[n] for n in function.name_in()])

    Phi_v = call(model.Phi_v)
    rate = v + ca.mtimes(Phi_v.T, mu)
    kinematic = [rate[i] for i in range(model.n_v)]
    for k in rotations:
        turn = dexp_inverse_sx(xi[k:k + 3], rate[k:k + 3])
        kinematic[k:k + 3] = [turn[0], turn[1], turn[2]]
    F = ca.vertcat(ca.vertcat(*kinematic), call(model.Q) - ca.mtimes(Phi_v.T, lam),
                   call(model.phi), ca.mtimes(Phi_v, v) - call(model.nu))
    J = ca.jacobian(F, ca.vertcat(xi, v, lam, mu))
    names = ["q0", "xi", "v", "lam", "mu"] + (["w", "wd"] if model.n_w else [])
    inputs = [q0, xi, v, lam, mu] + ([w, wd] if model.n_w else [])
    residual = ca.Function("ggl_residual", inputs, [F], names, ["F"])
    functions = {
        "residual": residual,
        "stages": residual.map(3),
        "start": ca.Function("ggl_start", inputs, [F, J, Phi_v], names, ["F", "J", "Phi_v"]),
    }
    return functions

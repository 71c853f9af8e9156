"""Sphinx directive ``config-reference``: the table of every configuration field, generated
from adparm's config dataclasses (section, key and default come from the code; the meaning from
the field's ``metadata["doc"]`` if it has one, else from DESCRIPTIONS below). A field without a
description, or a description without a field, is a warning, so ``sphinx-build -W`` fails until
the table is complete and true."""

from __future__ import annotations

import dataclasses

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from sphinx.util import logging

import adparm

logger = logging.getLogger(__name__)

#: (section, key) -> meaning, in reStructuredText.
DESCRIPTIONS = {
    ("plant", "p1"): "M(q) = [[p1 + 2 p3 cos q2, p2 + p3 cos q2], [p2 + p3 cos q2, p2]] "
    "(eq. 1); C follows from M. See :func:`adparm.two_link_parameters` for physical links.",
    ("plant", "p2"): "See p1.",
    ("plant", "p3"): "See p1.",
    ("plant", "g1"): "G(q) = [g1 cos q1 + g2 cos(q1 + q2), g2 cos(q1 + q2)] (N m); "
    "the paper's 9.8 x 1.2.",
    ("plant", "g2"): "See g1 (N m); the paper's 9.8.",
    ("plant", "coulomb"): "Friction F = coulomb sgn(dq) + viscous dq; the paper prints "
    "F = -0.1 sgn(dq). One number; with ``urdf`` one number or one per joint.",
    ("plant", "viscous"): "Viscous friction coefficient. Not in the paper. One number; with "
    "``urdf`` one number or one per joint.",
    ("plant", "disturbance"): "tau_d = [d1 sin t, d2 cos t] (N m).",
    ("plant", "urdf"): "A URDF file of any fixed-base serial arm (through Pinocchio) instead of "
    "the two-link arm: relative to the TOML file (in a config built from a dict, to the current "
    "directory), stored absolute. The actuated joints are its revolute, continuous and prismatic "
    "joints in model order; n follows from it and every sized setting takes the n-joint default. "
    '``"example-robot-data:ur5"`` names a robot of the example-robot-data package. '
    "p1 ... g2 may not be set with it; its default basis is ``structured`` (the arm's own: "
    "W* = [K; base inertial parameters]); the bases ``paper`` and ``augmented`` are refused. "
    "See :doc:`/guide/urdf-arms`.",
    ("plant", "gravity"): "Acceleration of gravity [gx, gy, gz] in the URDF's root frame "
    "(m/s^2); only with ``urdf``.",
    ("plant", "locked_joints"): "Joints of the URDF held at a position, a table "
    "``{name = position, ...}`` (rad or m), through Pinocchio's reduced model: their links "
    "become part of the parent body and n counts the free joints only. A mimic joint must be "
    "locked or follow a locked joint (it is then locked at multiplier x position + offset). An "
    "unknown name (the message lists the arm's joints) or a position outside the joint's limits "
    "is refused; only with ``urdf``. See :doc:`/guide/urdf-arms`.",
    ("model", "urdf"): "Another URDF of the same joint count as the controller's believed arm "
    "(a model error); only with ``plant.urdf``.",
    ("model", "gravity"): "The believed gravity [gx, gy, gz]; only with ``plant.urdf``.",
    ("model", "locked_joints"): "The believed locked joints (a table as ``plant.locked_joints``); "
    "the model must have the plant's number of free joints; only with ``plant.urdf``.",
    ("model", "p1"): "The arm the controller believes (feedforward h, f, g and W*). "
    "Each key left out takes the plant's value; set one to introduce a model error.",
    ("model", "p2"): "As p1.",
    ("model", "p3"): "As p1.",
    ("model", "g1"): "As p1.",
    ("model", "g2"): "As p1.",
    ("model", "coulomb"): "As p1.",
    ("model", "viscous"): "As p1.",
    ("task", "q0"): "Initial joint angles (rad).",
    ("task", "dq0"): "Initial joint velocities (rad/s). The paper is silent; 0 here.",
    ("task", "qd"): "Desired trajectory: a constant set-point (rad), or a ``[task.qd]`` table "
    "(below and :doc:`/guide/tracking`).",
    ("task.qd sinusoid", "amplitude"): '``kind = "sinusoid"``: qd_j = offset_j + sum_k '
    "amplitude_jk sin(frequency_jk t + phase_jk) (rad). A pair, or a 2 x n matrix for n "
    "sinusoids per joint.",
    ("task.qd sinusoid", "frequency"): "rad/s, same shape as amplitude.",
    ("task.qd sinusoid", "phase"): "rad, same shape as amplitude.",
    ("task.qd sinusoid", "offset"): "rad, one per joint.",
    ("task.qd samples", "t"): '``kind = "samples"``: sample times (s), from t <= 0 to '
    "t >= sim.T; qd through a cubic spline (SciPy's CubicSpline).",
    ("task.qd samples", "q"): "Samples of qd, one row [qd1, qd2] per time (rad).",
    ("task.qd samples", "file"): "Instead of t and q: a CSV file with columns t, qd1, qd2 "
    "(relative to the TOML file).",
    ("task.qd samples", "boundary"): "Spline end conditions: ``not-a-knot``, ``clamped`` or "
    "``natural``.",
    ("cost", "Q"): "4 x 4 state weight of r = x^T Q x + u^T R u (eqs. 10-11), symmetric "
    "positive definite.",
    ("cost", "R"): "2 x 2 input weight, symmetric positive definite.",
    ("control", "alpha1"): "Gain in e2 = de1 + alpha1 e1 (the paper's alpha); -alpha1 must be "
    "Hurwitz.",
    ("control", "ks"): "RISE gain (eqs. 27-28). Not printed in the paper.",
    ("control", "alpha2"): "RISE gain. Not printed in the paper.",
    ("control", "beta1"): "RISE gain; condition (29) bounds it from below "
    "(0.1 + 0.1/alpha2 = 0.2 < 0.5 here).",
    ("critic", "eta_c"): "Critic gain (eq. 23).",
    ("critic", "nu"): "Normalisation 1 + nu omega^T Gamma omega (eq. 24, corrected).",
    ("critic", "gamma0"): "Gamma(0) = gamma0 I; Gamma is reset to this value.",
    ("critic", "epsilon_T"): "Reset Gamma when its smallest eigenvalue falls below epsilon_T "
    "(< gamma0). See :doc:`/paper`.",
    ("actor", "eta_a1"): "Actor gain on the HJB-error gradient (eq. 26).",
    ("actor", "eta_a2"): "Actor gain pulling Wa towards Wc (eq. 26).",
    ("actor", "positive_e2"): "Not in the paper: the projection also keeps the e2 block of the "
    "actor's (and critic's) value positive definite at cos q2 = +-1 (the structured basis of a "
    "URDF arm: at qd(0), q(0) and the joint positions of the extrapolation box), which keeps "
    "learning away from the anti-stabilising HJB solution (see the truth guide).",
    ("actor", "e2_margin"): "The smallest eigenvalue the e2 block keeps when positive_e2 is on "
    "(units of M).",
    ("actor", "weight_bound"): "The projection keeps ||Wa|| <= weight_bound (the paper's "
    "proj{} has no printed bound).",
    ("init", "critic_weights"): "Wc(0), in the order of ``adparm.basis_names(config)``. Zero is "
    "inadmissible (:doc:`/paper`).",
    ("init", "actor_weights"): "Wa(0); it must stabilise the model.",
    ("probe", "amplitude"): "Probing torque probe_j = ramp(t) sum_k amplitude_jk "
    "sin(frequencies_k t + phases_jk), N m: one number (both joints), a pair (per joint) or a "
    "2 x n matrix (per joint and sinusoid). See :doc:`/paper` (excitation).",
    ("probe", "until"): "Probing stops at this time (s); 0 turns it off.",
    ("probe", "ramp"): "Linear fade-in time (s); 0 starts at full amplitude.",
    ("probe", "frequencies"): "rad/s, one per sinusoid.",
    ("probe", "phases"): "2 x n (rad). Equal phases on both joints keep each sinusoid along one "
    "torque direction.",
    ("controller", "kind"): "``adp`` (u = u_hat + probe; learns), ``rise`` (u = 0), ``pd`` "
    "(u = -(kp e1 + kd de1)) or ``optimal`` (u* = -R^-1 e2). See :doc:`/guide/baselines`.",
    ("controller", "basis"): "``augmented`` (the paper's functions with cos q2 = cos(qd2 - x2), "
    "exact for any qd), ``paper`` (the printed phi(x)), ``structured`` (e1 monomials and "
    "e2^T M_k(q) e2, :doc:`/guide/structured-basis`), ``quadratic``, ``polynomial`` (with "
    '``degree``), or a list of terms and families such as ``["quadratic", "x3^2*cos(q2)"]`` '
    "(:doc:`/guide/bases`). See also :doc:`/guide/tracking`. A URDF arm takes its own "
    "``structured`` basis by default (e1 products and e2^T M_b(q) e2 per base inertial "
    "parameter, :doc:`/guide/urdf-arms`) and refuses ``paper`` and ``augmented``.",
    ("controller", "degree"): "The highest (even) degree of the ``polynomial`` basis; only with "
    '``basis = "polynomial"``.',
    ("controller", "rise"): "Add the RISE term mu (eqs. 27-28); must be true with "
    '``kind = "rise"``.',
    ("controller", "kp"): "PD gain (a number times I, or 2 x 2), ``pd`` only.",
    ("controller", "kd"): "PD gain on de1, ``pd`` only.",
    ("extrapolation", "points"): "Number of extra states at which the HJB error enters the "
    "critic and actor laws; 0 is off (the paper). See :doc:`/guide/extrapolation`.",
    ("extrapolation", "box"): "Half-widths of the sampling box in x = [e1; e2] (one number or 4).",
    ("extrapolation", "mode"): "``fixed`` (drawn once in [-box, box]), ``grid`` (m per axis, "
    "points = m^4) or ``local`` (redrawn every step around x(t)).",
    ("extrapolation", "seed"): "Seed of the draws (MT19937, as NumPy's RandomState).",
    ("sim", "T"): "Horizon (s).",
    ("sim", "dt"): 'RK4 step (s), or ``"auto"``: the largest 1, 2 or 5 x 10^k s (at most 1 ms) '
    "at which every fast rate of the closed loop times dt is at most 0.6 of RK4's limit 2.785 "
    "(a URDF arm's default). An explicit step beyond the limit is refused before the run.",
    ("sim", "record_every"): "Record every n-th step.",
    (
        "sim",
        "divergence_bound",
    ): "The run stops as diverged when ``|q|``, ``|dq|``, ``|Wc|`` or ``|Wa|`` "
    "exceeds this value, or a state or recorded output is not finite.",
    ("diagnostics", "tolerance"): 'Verdict "ok" needs the critic weights, the actor weights '
    "and the applied policy (``rms |u_hat - u*| / rms |u*|`` over the last 10 % of the run) each "
    "within this relative distance of a known optimum; also the band of the summary's time "
    "within tolerance.",
}

#: Defaults that are None in the dataclasses, as the run resolves them.
RESOLVED_DEFAULTS = {
    ("model", "*"): "the plant's value",
    ("plant", "urdf"): "none (the built-in two-link arm)",
    ("plant", "gravity"): "[0, 0, -9.81] (with ``urdf``)",
    ("plant", "locked_joints"): "none (every joint free)",
    ("critic", "epsilon_T"): "1e-6; 1e-3 with extrapolation points",
    ("probe", "phases"): "k rad for sinusoid k, both joints",
    ("task.qd sinusoid", "phase"): "zeros",
    ("task.qd samples", "file"): "none",
    ("controller", "degree"): "none (only with the polynomial basis, where it must be set)",
    ("init", "*"): "the basis' default: all ones (paper, augmented); [1, 0, 1, p1, p2, p3] "
    "(structured: K = I and the believed model's inertia; on a URDF arm the model's base "
    "inertial parameters)",
}


def _format(value):
    if isinstance(value, tuple):
        return "[" + ", ".join(_format(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


def _sections():
    config = adparm.Config()
    for section in dataclasses.fields(config):
        if not section.name.startswith("_"):  # Config._explicit: not a section
            yield section.name, getattr(config, section.name)
    yield "task.qd sinusoid", adparm.SinusoidTrajectory()
    yield "task.qd samples", adparm.SampledTrajectory(t=(0.0, 1.0), q=((0.0, 0.0), (0.0, 0.0)))


def _default(section, key, instance):
    field = next(f for f in dataclasses.fields(instance) if f.name == key)
    raw = field.default if field.default is not dataclasses.MISSING else field.default_factory()
    if raw is None:
        resolved = RESOLVED_DEFAULTS.get((section, key)) or RESOLVED_DEFAULTS.get((section, "*"))
        if resolved is None:
            logger.warning(f"config-reference: {section}.{key} defaults to None; say what it means")
            return "None"
        return resolved
    if section == "task.qd samples" and key in ("t", "q"):
        return "[]"
    return "``" + _format(getattr(instance, key) if section != "task.qd samples" else raw) + "``"


class ConfigReference(Directive):
    has_content = False

    def run(self):
        lines = []
        seen = set()
        for section, instance in _sections():
            header = f"[{section.split()[0]}]" + (
                f' with kind = "{section.split()[1]}"' if " " in section else ""
            )
            lines += [f".. list-table:: {header}", "   :header-rows: 1", "   :widths: 18 22 60", ""]
            lines += ["   * - key", "     - default", "     - meaning"]
            for field in dataclasses.fields(instance):
                seen.add((section, field.name))
                description = field.metadata.get("doc") or DESCRIPTIONS.get((section, field.name))
                if description is None:
                    logger.warning(
                        f"config-reference: {section}.{field.name} has no description in "
                        "docs/_ext/config_reference.py"
                    )
                    description = "(undocumented)"
                default = _default(section, field.name, instance)
                lines += [f"   * - ``{field.name}``", f"     - {default}", f"     - {description}"]
            lines.append("")
        for stale in sorted(set(DESCRIPTIONS) - seen):
            logger.warning(f"config-reference: {'.'.join(stale)} is described but not a field")
        holder = nodes.container()
        self.state.nested_parse(StringList(lines, source="config-reference"), 0, holder)
        return holder.children


def setup(app):
    app.add_directive("config-reference", ConfigReference)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

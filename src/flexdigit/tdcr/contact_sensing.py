"""A point contact on a tendon robot, located and measured in space from its strain gauges.

A force ``F`` (world frame) pressed at arc length ``s_c`` changes the bending and twisting moment of every
cross-section between the base and ``s_c`` by ``(p(s_c) - p(s)) x F`` and of none beyond it. To first order in
``F`` about the shape without the contact (the twin's, under the known tensions), a gauge station at ``s < s_c``
sees the curvature change

    du(s) = Kbt^-1 R(s)^T [(p(s_c) - p(s)) x F]

which is linear in ``F`` for a given ``s_c``. :func:`locate_contact` fits ``F`` by least squares at every
candidate ``s_c`` (every ``step_m`` along the backbone) and keeps the ``s_c`` whose fit leaves the smallest
residual: the thesis's planar localisation (the moment's slope along the digit gives the force, its zero the
place) in three dimensions.

That first-order fit is the start. Given the tensions, :func:`locate_contact` then fits place and force to the
readings through the twin itself (the discrete rod pressed by the force, spread linearly between the two nodes
around ``s_c``, settled by Newton; ``scipy.optimize.least_squares``): a 50 mN push bends rao2021 by tens of
millimetres, where the first-order fit's force was 15-25 % off. The fit's one-sigma uncertainty (``s_std_m``,
``force_std_n``) comes from its Jacobian and the readings' noise (or the residual's estimate of it, per degree
of freedom, if larger).

Where the gauges cannot see it, it says so:

- a contact between the base and the second gauge station (``visible_from_m``) changes the moment at one station
  at most, which cannot tell the place from the force: the fit is not attempted there;
- the component of ``F`` along the lever arms ``p(s_c) - p(s)`` of every seeing station makes no moment (on a
  straight rod, the axial push): it is reported as ``unseen_direction`` and left out of ``force_n``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_real
from flexdigit.errors import ParameterError
from flexdigit.tdcr import _chain_kernel
from flexdigit.tdcr.description import Robot
from flexdigit.tdcr.dynamics import _discrete_model, _element_frames
from flexdigit.tdcr.sensing import GaugeLayout, _station_curvatures, gauge_layout, gauge_strains
from flexdigit.tdcr.statics import StaticSolution, _nodes, solve_statics

__all__ = ["ContactEstimate", "ContactSensing", "locate_contact", "pressed_shape", "sense_contact"]


@dataclass(frozen=True)
class ContactEstimate:
    """A point contact estimated from gauge readings.

    Attributes
    ----------
    s_m : float
        Its arc length from the base (m).
    position_m : ndarray (3,)
        Where it is, world frame (on the twin's shape without it).
    force_n : ndarray (3,)
        The force on the robot (N, world frame), less any ``unseen_direction`` component.
    unseen_direction : ndarray (3,) or None
        A unit vector along which the force makes no moment at any seeing station (so is not measured), or None.
    visible_from_m : float
        Contacts nearer the base than this (the second gauge station) cannot be located.
    residual : float
        RMS of the curvature change the first-order fit leaves (1/m).
    refined : bool
        Whether place and force were fitted through the twin (nonlinear; else first order about ``free``).
    s_std_m : float or None
        One-sigma uncertainty of ``s_m`` (m) from the refined fit's Jacobian, or None when not refined.
    force_std_n : ndarray (3,) or None
        One-sigma uncertainty of each component of ``force_n`` (N), or None when not refined.
    strain_rms : float or None
        RMS of the strain readings the refined fit leaves.
    """

    s_m: float
    position_m: np.ndarray
    force_n: np.ndarray
    unseen_direction: np.ndarray | None
    visible_from_m: float
    residual: float
    refined: bool = False
    s_std_m: float | None = None
    force_std_n: np.ndarray | None = None
    strain_rms: float | None = None

    __repr__ = fields_summary

    @property
    def out_of_sight(self) -> bool:
        """Whether the estimate sits at the sight limit ``visible_from_m`` (within 1 mm): a contact there or
        nearer the base changes one gauge station at most, so its place and force are not determined."""
        return self.s_m <= self.visible_from_m + _SIGHT_MARGIN_M


def _interp(s_nodes, values, s):
    return np.stack([np.interp(s, s_nodes, values[:, k]) for k in range(values.shape[1])], axis=-1)


def locate_contact(
    robot: Robot,
    layout: GaugeLayout,
    strains,
    free: StaticSolution,
    *,
    step_m: float = 1e-3,
    tensions_n=None,
    nodes_per_disk: int = 2,
    noise_std: float = 0.0,
) -> ContactEstimate:
    """The contact's place and force from the gauge ``strains``, given the twin's shape ``free`` without it.

    Parameters
    ----------
    robot : Robot
    layout : GaugeLayout
        Where the gauges are (two faces at every station at least).
    strains : array (g,)
        The readings with the contact, in the layout's order.
    free : StaticSolution
        The twin under the same tensions and known loads, without the contact.
    step_m : float
        Spacing of the candidate places (m).
    tensions_n : sequence of float, optional
        The tensions ``free`` was solved under: given, the first-order estimate is refined through the twin
        (:func:`pressed_shape`'s discrete rod at ``nodes_per_disk``); None, it is returned as it is.
    nodes_per_disk : int
        The twin's nodes per disk interval for the refinement.
    noise_std : float
        The readings' noise (strain), for the refined estimate's uncertainty.
    """
    owner = "locate_contact"
    strains = check_array(strains, "strains", owner, shape=layout.s_m.shape)
    step_m = check_real(step_m, "step_m", owner, low=0.0, low_open=True)
    noise_std = check_real(noise_std, "noise_std", owner, low=0.0)
    first = _first_order(robot, layout, strains, free, step_m)
    if tensions_n is None:
        return first
    return _refined(first, _Twin(robot, tensions_n, nodes_per_disk), layout, strains, noise_std)


def _first_order(robot, layout, strains, free, step_m) -> ContactEstimate:
    """The first-order fit about ``free``: the best of a least-squares force at every candidate place."""
    owner = "locate_contact"
    stations, measured = _station_curvatures(layout, strains)
    _, baseline = _station_curvatures(layout, gauge_strains(free, layout))
    if stations.size < 2:
        raise ParameterError(f"{owner}: the gauges sit at {stations.size} station(s); locating needs two or more.")
    du = (measured - baseline)[:, :3]
    seen = np.any(layout._columns(np.ones(layout.s_m.size, bool))[:, 2] != 0)  # a tilted gauge: twist seen
    rows = [0, 1, 2] if seen else [0, 1]
    kbt = robot.backbone.bending_torsion_stiffness
    s_nodes = free.s_m
    p_st = _interp(s_nodes, free.positions_m, stations)
    r_st = _interp(s_nodes, free.rotations.reshape(-1, 9), stations).reshape(-1, 3, 3)
    candidates = np.arange(stations[1], s_nodes[-1] + 0.5 * step_m, step_m)
    best = None
    for s_c in candidates:
        p_c = _interp(s_nodes, free.positions_m, np.array([s_c]))[0]
        near = stations < s_c
        blocks, targets = [], []
        for k in np.flatnonzero(near):
            arm = p_c - p_st[k]
            hat = np.array([[0.0, -arm[2], arm[1]], [arm[2], 0.0, -arm[0]], [-arm[1], arm[0], 0.0]])
            blocks.append(((r_st[k].T @ hat) / kbt[:, None])[rows])
            targets.append(du[k, rows])
        design, target = np.vstack(blocks), np.concatenate(targets)
        far = du[~near][:, rows].ravel()  # beyond the contact, no change is predicted
        force, *_ = np.linalg.lstsq(design, target, rcond=1e-9)
        left = np.concatenate([design @ force - target, far])
        residual = float(np.sqrt(np.mean(left**2)))
        if best is None or residual < best[0]:
            best = (residual, s_c, p_c, force, design)
    residual, s_c, p_c, force, design = best
    _, sing, vt = np.linalg.svd(design)
    unseen = vt[-1] if sing[-1] < 1e-6 * sing[0] else None
    return ContactEstimate(
        s_m=float(s_c),
        position_m=p_c,
        force_n=force,
        unseen_direction=unseen,
        visible_from_m=float(stations[1]),
        residual=residual,
    )


class _Twin:
    """The discrete rod under fixed tensions, pressed by a point force anywhere: the force at arc length ``s``
    spread linearly over the two nodes around it (exactly the node's force at a node), settled by Newton from
    the last equilibrium found (or the shot rod's shape)."""

    def __init__(self, robot: Robot, tensions_n, nodes_per_disk: int):
        start = solve_statics(robot, tensions_n, nodes_per_disk=nodes_per_disk)  # checks the tensions
        self.robot = robot
        self.nodes, ends = _nodes(robot, nodes_per_disk)
        loads = (np.asarray(tensions_n, dtype=float), np.zeros(3), np.zeros(3), np.zeros(3))
        self.model, _, _, self.hb = _discrete_model(robot, self.nodes, ends, loads)
        self.unloaded = self.model[4].copy()
        self.start = (start.positions_m.copy(), np.ascontiguousarray(_element_frames(start.rotations)))
        self.last = self.start

    def press(self, s_m: float | None = None, force_n=None, *, at_node: bool = False) -> StaticSolution | None:
        """The equilibrium pressed by ``force_n`` at ``s_m`` (at the nearest node if ``at_node``), or None if
        Newton finds none."""
        added = np.zeros_like(self.unloaded)
        if force_n is not None:
            nodes = self.nodes
            if at_node:
                added[int(np.argmin(np.abs(nodes - s_m)))] += force_n
            else:
                i = int(np.clip(np.searchsorted(nodes, s_m, side="right") - 1, 0, nodes.size - 2))
                w = (s_m - nodes[i]) / (nodes[i + 1] - nodes[i])
                added[i] += (1.0 - w) * np.asarray(force_n)
                added[i + 1] += w * np.asarray(force_n)
        for x0, q0 in (self.last, self.start):
            found = self._settle(x0, q0, added)
            if found is not None:
                break
        else:  # Newton's basin missed from either start: the force ramped up from the unloaded rod
            x, q = self.start
            for factor in np.arange(1, _RAMP_STEPS + 1) / _RAMP_STEPS:
                found = self._settle(x, q, factor * added)
                if found is None:
                    return None
                x, q = found
        self.last = found
        return self._solution(*found)

    def _settle(self, x0, q0, added):
        self.model[4][:] = self.unloaded + added
        x, q = x0.copy(), q0.copy()
        if _chain_kernel.equilibrate(x, q, self.model, self.hb, 1e-10, 100) == _chain_kernel.NO_PROGRESS:
            return None
        return x, q

    def _solution(self, x, q) -> StaticSolution:
        n = self.nodes.size - 1
        sig, kap = np.empty((n, 3)), np.empty((n, 3))
        _chain_kernel._state_strains(x, q, self.model, sig, kap)
        frames = np.empty((1, n + 1, 3, 3))
        _chain_kernel.node_frames(q[None], frames)
        strains = np.zeros((n + 1, 6))
        v = sig + [0.0, 0.0, 1.0]
        strains[0, :3], strains[-1, :3] = v[0], v[-1]
        strains[1:-1, :3] = (v[:-1] + v[1:]) / 2
        strains[:-1, 3:] = kap  # element curvatures at their first node; the tip carries no moment
        return StaticSolution(self.nodes, x, frames[0], strains, strains, np.zeros(6), True, 0, 0.0)


_SIGHT_MARGIN_M = 1e-3  # the first-order scan's default step
_RAMP_STEPS = 8  # a force Newton cannot take at once, in eighths (rao2021 under tensions: 100 mN and more)
_STRAIN_SCALE = 1e-6  # the fit's residuals in microstrain, a good amplifier's noise
_FORCE_SCALE_N = 0.01  # and its unknowns in 10 mN and ...
_PLACE_SCALE_M = 0.01  # ... 10 mm: all of order one


def _refined(first: ContactEstimate, twin: _Twin, layout: GaugeLayout, strains, noise_std) -> ContactEstimate:
    """Place and force fitted to ``strains`` through ``twin`` (a trust-region least squares from the first-order
    estimate). All three force components are fitted: a direction that makes no moment on the shape without the
    contact (the axial push on a straight rod) makes one on the shape the rest of the force bends; it stays
    ``unseen_direction`` only where the fit's Jacobian is blind to it too. The first-order estimate, unchanged but
    for its flag, if the twin finds no equilibrium at the start."""
    from scipy.optimize import least_squares

    length = twin.robot.length_m
    low, high = first.visible_from_m, length

    def unpack(theta):
        return theta[0] * _PLACE_SCALE_M, theta[1:] * _FORCE_SCALE_N

    def residual(theta):
        s_c, force = unpack(theta)
        shape = twin.press(float(np.clip(s_c, low, high)), force)
        if shape is None:
            return np.full(strains.size, 1e3)  # no equilibrium: far from any reading
        return (gauge_strains(shape, layout) - strains) / _STRAIN_SCALE

    theta0 = np.concatenate([[np.clip(first.s_m, low, high) / _PLACE_SCALE_M], first.force_n / _FORCE_SCALE_N])
    if twin.press(first.s_m, first.force_n) is None:
        return first
    fit = least_squares(
        residual,
        theta0,
        bounds=(
            [low / _PLACE_SCALE_M] + [-np.inf] * 3,
            [high / _PLACE_SCALE_M] + [np.inf] * 3,
        ),
        diff_step=1e-4,
        x_scale=1.0,
        ftol=1e-12,
        xtol=1e-10,
    )
    s_c, force = unpack(fit.x)
    shape = twin.press(s_c, force)
    if shape is None:
        return first
    rms = float(np.sqrt(np.mean(fit.fun**2))) * _STRAIN_SCALE
    dof = max(strains.size - fit.x.size, 1)
    sigma = max(noise_std, rms * np.sqrt(strains.size / dof))  # the noise, or the residual's estimate of it
    jac = fit.jac / np.concatenate([[_PLACE_SCALE_M], [_FORCE_SCALE_N] * 3]) * _STRAIN_SCALE
    _, sing, vt = np.linalg.svd(fit.jac[:, 1:])  # the force's directions, in the fit's units
    unseen = vt[-1] if sing[-1] < 1e-6 * sing[0] else None
    cov = sigma**2 * np.linalg.pinv(jac.T @ jac, rcond=1e-9)
    force_cov = cov[1:, 1:]
    return ContactEstimate(
        s_m=float(s_c),
        position_m=_interp(shape.s_m, shape.positions_m, np.array([s_c]))[0],
        force_n=force if unseen is None else force - (force @ unseen) * unseen,
        unseen_direction=unseen,
        visible_from_m=first.visible_from_m,
        residual=first.residual,
        refined=True,
        s_std_m=float(np.sqrt(cov[0, 0])),
        force_std_n=np.sqrt(np.diag(force_cov)),
        strain_rms=rms,
    )


def pressed_shape(
    robot: Robot, tensions_n, *, contact_s_m: float | None = None, contact_force_n=None, nodes_per_disk: int = 2
) -> StaticSolution:
    """The robot's equilibrium under ``tensions_n`` and a point force ``contact_force_n`` (N, world frame) at the
    node nearest ``contact_s_m`` (m from the base), or none: the discrete rod (:mod:`flexdigit.tdcr.dynamics`,
    which takes a force at any node) settled by Newton, from the shot rod's shape.

    The shape without a contact is the same model's, so that what :func:`locate_contact` sees between the two is
    the contact, not a difference of models (the discrete rod is second order in its element length: 0.7 mm from
    the shot statics on rao2021 at 4 elements a disk).

    Raises
    ------
    ParameterError
        Naming the bad argument; also if the rod finds no equilibrium (a force that buckles it).
    """
    owner = "pressed_shape"
    twin = _Twin(robot, tensions_n, nodes_per_disk)
    force = s_c = None
    if contact_force_n is not None:
        force = check_array(contact_force_n, "contact_force_n", owner, shape=(3,))
        if contact_s_m is None:
            raise ParameterError(f"{owner}: a contact force needs its place, contact_s_m (m from the base)")
        s_c = check_real(contact_s_m, "contact_s_m", owner, low=0.0, high=robot.length_m, low_open=True)
    twin.last = twin.start
    shape = twin.press(s_c, force, at_node=True)
    if shape is None:
        raise ParameterError(
            f"{owner}: the rod of {robot.name!r} finds no equilibrium under these tensions and this contact "
            "(a force that large buckles it)"
        )
    return shape


@dataclass(frozen=True)
class ContactSensing:
    """What :func:`sense_contact` found.

    Attributes
    ----------
    layout : GaugeLayout
    strains : ndarray (g,)
        The readings with the contact (the pressed twin's, with any noise, or given).
    estimate : ContactEstimate
    free : StaticSolution
        The twin's shape without the contact, about which the estimate is made.
    true_s_m : float or None
        Where the twin was pressed (the node nearest the asked place), when it was.
    true_force_n : ndarray (3,) or None
        The force it was pressed with.
    """

    layout: GaugeLayout
    strains: np.ndarray
    estimate: ContactEstimate
    free: StaticSolution
    true_s_m: float | None = None
    true_force_n: np.ndarray | None = None

    @property
    def place_error_m(self) -> float | None:
        """``|estimated - true|`` arc length (m)."""
        return None if self.true_s_m is None else abs(self.estimate.s_m - self.true_s_m)

    @property
    def force_error_n(self) -> float | None:
        """``|estimated - true force|`` (N), the true force less its component along ``unseen_direction``."""
        if self.true_force_n is None:
            return None
        seen = self.true_force_n
        unseen = self.estimate.unseen_direction
        if unseen is not None:
            seen = seen - (seen @ unseen) * unseen
        return float(np.linalg.norm(self.estimate.force_n - seen))

    def to_dict(self) -> dict:
        """Plain values: the estimate (``s_m``, ``position_m``, ``force_n``, ...), and the truth and errors."""
        est = self.estimate
        hidden = est.out_of_sight  # no plausible number where the gauges cannot tell
        return {
            "gauges": int(self.layout.s_m.size),
            "strains": self.strains.tolist(),
            "out_of_sight": hidden,
            "s_m": None if hidden else est.s_m,
            "position_m": None if hidden else est.position_m.tolist(),
            "force_n": None if hidden else est.force_n.tolist(),
            "unseen_direction": None if est.unseen_direction is None else est.unseen_direction.tolist(),
            "visible_from_m": est.visible_from_m,
            "residual_per_m": est.residual,
            "refined": est.refined,
            "s_std_m": est.s_std_m,
            "force_std_n": None if est.force_std_n is None else est.force_std_n.tolist(),
            "strain_rms": est.strain_rms,
            "true_s_m": self.true_s_m,
            "true_force_n": None if self.true_force_n is None else self.true_force_n.tolist(),
            "place_error_m": self.place_error_m,
            "force_error_n": self.force_error_n,
        }

    __repr__ = fields_summary


def sense_contact(
    robot: Robot,
    tensions_n,
    strains=None,
    *,
    layout: GaugeLayout | None = None,
    contact_s_m: float | None = None,
    contact_force_n=None,
    noise_std: float = 0.0,
    seed: int | None = None,
    stations_per_segment: int = 4,
    nodes_per_disk: int = 2,
    step_m: float = 1e-3,
) -> ContactSensing:
    """A point contact's place and force from the gauges: given ``strains``, or the twin's readings pressed at
    ``contact_s_m`` by ``contact_force_n`` (with ``noise_std`` of seeded white noise), about the twin's shape
    under ``tensions_n`` without it (:func:`pressed_shape`, :func:`locate_contact`).

    Examples
    --------
    >>> from flexdigit.tdcr import Robot, Segment
    >>> rod = Robot(name="rod", segments=(Segment(0.4, 40),))
    >>> found = sense_contact(rod, [], contact_s_m=0.3, contact_force_n=[0.01, 0, 0])
    >>> round(found.estimate.s_m, 3), bool(found.force_error_n < 1e-3)
    (0.3, True)
    """
    owner = "sense_contact"
    layout = gauge_layout(robot, stations_per_segment) if layout is None else layout
    if not isinstance(layout, GaugeLayout):
        raise ParameterError(f"The 'layout' parameter of {owner} must be a GaugeLayout. Got {type(layout).__name__}.")
    free = pressed_shape(robot, tensions_n, nodes_per_disk=nodes_per_disk)
    true_s = true_force = None
    if strains is None:
        if contact_force_n is None:
            raise ParameterError(
                f"{owner}: give the gauges' readings (strains) or a contact to press the twin with (contact_s_m, "
                "contact_force_n)"
            )
        pressed = pressed_shape(
            robot, tensions_n, contact_s_m=contact_s_m, contact_force_n=contact_force_n, nodes_per_disk=nodes_per_disk
        )
        true_s = float(free.s_m[int(np.argmin(np.abs(free.s_m - contact_s_m)))])
        true_force = np.asarray(contact_force_n, dtype=float)
        noise_std = check_real(noise_std, "noise_std", owner, low=0.0)
        strains = gauge_strains(pressed, layout, noise_std=noise_std, seed=seed)
    strains = check_array(strains, "strains", owner, shape=layout.s_m.shape)
    estimate = locate_contact(
        robot,
        layout,
        strains,
        free,
        step_m=step_m,
        tensions_n=tensions_n,
        nodes_per_disk=nodes_per_disk,
        noise_std=noise_std,
    )
    return ContactSensing(layout, strains, estimate, free, true_s, true_force)

"""Penalty contact and Coulomb friction on the skin's top-layer masses, compiled.

Per step, for every contact whose trajectory runs, for every free top-layer mass near its
indenter (within the indenter's reach plus ``margin_m`` of its axis, by rest position), with
the mass's current position ``p`` and velocity ``v``, the indenter's axis ``(x, y)``, tip
height ``z_tip`` and velocity ``u`` (from its pose one step back):

    δ  = p_z − (z_tip + h(p_x − x, p_y − y))               penetration (m), h: indenters.py
    N  = k_n·δ + c_n·(v_z − u_z)                            normal force (N), if δ > 0, N > 0
    f  = −k_t·(d − a)                                       stick spring (N), d = p_xy − (x, y)
    |f| ≤ μ_s·N (a sticking mass) or ≤ μ_k·N (a slipping one): it sticks and gets
    f − c_t·(v_xy − u_xy) (at most μ_s·N); else it slips: f ← μ_k·N·f/|f| and its anchor
    a ← d + f/k_t (the stick spring then holds exactly f)

A mass that comes into contact sticks with its anchor ``a`` where it touched (in the
indenter's frame, so the indenter drags it). The mass gets ``(f_x, f_y, −N)``, added to the
top layer exactly as a stimulus's force is, held over the step. Per contact the kernel writes
the ground truth (:mod:`skinhil.world.truth`).

Parameters (:class:`ContactParams`, at the default skin; :meth:`ContactParams.for_skin`
scales them with any other skin's stiffness): ``k_n = 50,000 N/m`` per mass, about 4x the
vertical stiffness a top-layer mass has in the skin (about 13,000 N/m: its four springs to
layer 2 at 5,000 N/m, 2/3 of each along z), so the indenter is firm (a held depth is 80 %
surface displacement, 20 % penetration) without setting the step: the fastest contact mode
``sqrt((k_n + 13,000)/m)`` is 2,500 rad/s, ``ω·dt = 0.25`` at 0.1 ms. A force held over a step
lags the state by half a step, which feeds a penalty spring energy at a rate like a negative
damper ``k·dt/2``; the contact's dampers are chosen above it (``c_n = 5 ≥ k_n·dt``,
``c_t = 2 ≥ k_t·dt`` N·s/m at dt ≤ 0.1 ms), so the contact only takes energy out:
:meth:`ContactParams.check` refuses a step where they would not. ``k_t = 20,000 N/m``: the
stick spring, near the skin's own in-plane stiffness at a mass. Every constant scales with
the skin (x0.01 on the paper regime's skin, ``--amplitude paper``), the admittances inversely,
so the contact's modes, its force control's loop gain and its forces at a given load are the
same on both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numba
import numpy as np

from skinhil.errors import ConfigError
from skinhil.validation import Constraints, positive, validate_params
from skinhil.world.indenters import surface_height
from skinhil.world.truth import (
    T_ACTIVE,
    T_AREA,
    T_DEPTH,
    T_FX,
    T_FY,
    T_IX,
    T_IY,
    T_LOAD,
    T_NODES,
    T_NORMAL,
    T_SLIP,
    T_SLIP_SPEED,
    T_X,
    T_Y,
)

MAX_DEPTH_M = 5e-3
"""A force-controlled indenter goes at most this deep (m) below the rest surface."""
STICK, SLIP = 1, 2
"""A touching mass's friction state (0: not touching)."""


@dataclass(frozen=True)
class ContactParams:
    """Penalty and friction constants (module docstring), per top-layer mass."""

    normal_stiffness_n_per_m: float = 50_000.0
    normal_damping_n_s_per_m: float = 5.0
    tangential_stiffness_n_per_m: float = 20_000.0
    tangential_damping_n_s_per_m: float = 2.0
    admittance_m_per_n_s: float = 0.01
    """Normal force control: the indenter moves at this speed (m/s) per newton of load error:
    a loop gain b·k_n·dt of 0.05 per touching mass at 0.1 ms, so it settles in ~10 ms on one
    mass (the penalty spring in series with the skin), faster on more, and stays stable up to
    ~20 touching masses (a force-controlled pad wider than that needs a lower one)."""
    tangential_admittance_m_per_n_s: float = 0.02
    """Tangential force control (the grasp's load): an object pulled past its friction slides
    at this speed per newton of excess load (6 mm/s at 0.3 N), with a stick loop gain
    b_t·k_t·dt of 0.04 per touching mass."""
    margin_m: float = 2e-3
    """Masses whose rest position is within reach + margin of the axis are tested."""

    _parameter_constraints: ClassVar[Constraints] = {
        "normal_stiffness_n_per_m": positive("N/m"),
        "normal_damping_n_s_per_m": positive("N·s/m"),
        "tangential_stiffness_n_per_m": positive("N/m"),
        "tangential_damping_n_s_per_m": positive("N·s/m"),
        "admittance_m_per_n_s": positive("m/(N·s)"),
        "tangential_admittance_m_per_n_s": positive("m/(N·s)"),
        "margin_m": positive("m"),
    }

    def __post_init__(self) -> None:
        validate_params(self)

    @classmethod
    def for_skin(cls, stiffness_n_per_m: float, reference_n_per_m: float) -> ContactParams:
        """The defaults for a skin of spring stiffness ``stiffness_n_per_m`` (N/m), made for
        one of ``reference_n_per_m`` (the default skin's): stiffnesses and dampers scaled by
        their ratio, the admittance by its inverse (module docstring)."""
        f = stiffness_n_per_m / reference_n_per_m
        d = cls()
        return cls(d.normal_stiffness_n_per_m * f, d.normal_damping_n_s_per_m * f,
                   d.tangential_stiffness_n_per_m * f, d.tangential_damping_n_s_per_m * f,
                   d.admittance_m_per_n_s / f, d.tangential_admittance_m_per_n_s / f,
                   d.margin_m)

    def check(self, dt_s: float, mass_kg: float) -> None:
        """:class:`ConfigError` unless the contact is stable and takes energy out at step
        ``dt_s`` (s) on masses of ``mass_kg`` (module docstring)."""
        if (self.normal_damping_n_s_per_m < 0.5 * self.normal_stiffness_n_per_m * dt_s
                or self.tangential_damping_n_s_per_m
                < 0.5 * self.tangential_stiffness_n_per_m * dt_s):
            raise ConfigError(f"contact at dt {dt_s:g} s: a held penalty force would create "
                              "energy (damping below stiffness x dt/2); lower --dt")
        omega = math.sqrt(self.normal_stiffness_n_per_m / mass_kg)
        if omega * dt_s > 1.0:
            raise ConfigError(f"contact at dt {dt_s:g} s: the penalty spring's mode "
                              f"(omega·dt = {omega * dt_s:.2f}) is not resolved; lower --dt")


class ContactOperands(NamedTuple):
    """What the compiled contact step reads of a scene on a skin
    (:attr:`skinhil.world.scene.World.operands`, built there)."""

    columns: np.ndarray
    """Each top-layer mass's (row-major) column in the stepper's state; -1 where fixed."""
    rest_xy: np.ndarray
    """The top-layer masses' rest positions (n_top, 2) m."""
    rows: int
    """Top-layer rows."""
    cols: int
    """Top-layer columns."""
    spacing: float
    """Mass spacing (m)."""
    kn: float
    """Normal stiffness (N/m)."""
    cn: float
    """Normal damping (N·s/m)."""
    kt: float
    """Tangential (stick) stiffness (N/m)."""
    ct: float
    """Tangential damping (N·s/m)."""
    bn: float
    """Normal force control's admittance (m/s per N)."""
    bt: float
    """Tangential force control's admittance (m/s per N)."""
    margin: float
    """Masses within reach plus this (m) of an axis are tested."""
    shapes: np.ndarray
    """Per contact, its indenter's code (:mod:`skinhil.world.indenters`)."""
    geos: np.ndarray
    """Per contact, its indenter's geometry."""
    reach: np.ndarray
    """Per contact, its indenter's reach from the axis (m)."""
    starts: np.ndarray
    """Per contact, its start (s, scene time)."""
    key_ptr: np.ndarray
    """Per contact, where its keyframes start in :attr:`keys` (CSR pointers)."""
    keys: np.ndarray
    """Every contact's keyframes (t s, x m, y m, depth m or load N), one after the other."""
    control: np.ndarray
    """Per contact, whether the normal and the tangential axes are force-controlled."""
    vib: np.ndarray
    """Per contact, its vibration's amplitude (m), frequency (Hz) and axis (0, 1, 2)."""
    mu: np.ndarray
    """Per contact, its static and kinetic friction coefficients."""
    origin: np.ndarray
    """Per contact, where a force-controlled tangential axis starts (x, y) m."""


class ContactState(NamedTuple):
    """What the compiled contact step updates in place (:attr:`skinhil.world.scene.World.
    state`)."""

    pose: np.ndarray
    """Per contact, its pose (x, y, z_tip) m now."""
    prev: np.ndarray
    """... and a step back."""
    meas: np.ndarray
    """Per contact, the last measured force (Fx, Fy, N) N."""
    live: np.ndarray
    """Per contact, whether it runs."""
    setpoint: np.ndarray
    """Per contact, the load set-point (N; NaN: the trajectory's)."""
    nodes: np.ndarray
    """Per contact and top-layer mass, its friction state (0, :data:`STICK`, :data:`SLIP`)."""
    anchor: np.ndarray
    """Per contact and top-layer mass, its stick spring's anchor (m, the indenter's frame)."""
    stamp: np.ndarray
    """Per contact and top-layer mass, the last step it touched."""
    counter: np.ndarray
    """The step counter (1,)."""


@numba.njit(cache=True, nogil=True)
def contact_forces(t_s: float, dt_s: float, q: np.ndarray, v: np.ndarray, out: np.ndarray,
                   ops: ContactOperands, state: ContactState,
                   truth: np.ndarray) -> None:  # pragma: no cover - compiled
    """Add the contacts' forces (N) at scene time ``t_s`` (s) into ``out`` (3, n) from the
    displacements ``q`` (3, n) m and velocities ``v`` (3, n) m/s; write each contact's truth
    row into ``truth`` (n_contacts, RAW_FIELDS) (module docstring)."""
    index, rest_xy, spacing, shapes, geos, reach = (ops.columns, ops.rest_xy, ops.spacing,
                                                    ops.shapes, ops.geos, ops.reach)
    starts, key_ptr, keys, control, vib, mu = (ops.starts, ops.key_ptr, ops.keys, ops.control,
                                               ops.vib, ops.mu)
    pose, prev, meas, live = state.pose, state.prev, state.meas, state.live
    setpoint, nodes, anchor, stamp = state.setpoint, state.nodes, state.anchor, state.stamp
    state.counter[0] += 1
    now = state.counter[0]
    kn, cn, kt, ct, bn, bt = ops.kn, ops.cn, ops.kt, ops.ct, ops.bn, ops.bt
    rows, cols = ops.rows, ops.cols
    half_w = 0.5 * (cols - 1) * spacing
    half_h = 0.5 * (rows - 1) * spacing
    for c in range(shapes.shape[0]):
        tr = truth[c]
        tr[:] = 0.0
        tr[T_LOAD] = np.nan
        k0, k1 = key_ptr[c], key_ptr[c + 1]
        tau = t_s - starts[c]
        if tau < 0.0 or tau > keys[k1 - 1, 0]:
            live[c] = 0
            continue
        kk = keys[k0:k1]
        x = np.interp(tau, kk[:, 0], kk[:, 1])
        y = np.interp(tau, kk[:, 0], kk[:, 2])
        val = np.interp(tau, kk[:, 0], kk[:, 3])
        wob = 0.0
        if vib[c, 0] > 0.0:
            wob = vib[c, 0] * math.sin(2.0 * math.pi * vib[c, 1] * tau)
        axis = int(vib[c, 2])
        if control[c, 1] == 0:
            if axis == 0:
                x += wob
            elif axis == 1:
                y += wob
        elif live[c] == 0:
            x, y = ops.origin[c, 0], ops.origin[c, 1]
        else:
            x = pose[c, 0] + dt_s * bt * (x - meas[c, 0])
            y = pose[c, 1] + dt_s * bt * (y - meas[c, 1])
        if control[c, 0] == 0:
            z = -val
            if axis == 2:
                z -= wob
        else:
            load = setpoint[c] if not math.isnan(setpoint[c]) else val
            tr[T_LOAD] = load
            z = 0.0 if live[c] == 0 else pose[c, 2] - dt_s * bn * (load - meas[c, 2])
            z = max(z, -MAX_DEPTH_M)
            if load <= 0.0:
                z = max(z, 0.0)
        if live[c] == 0:
            prev[c, 0], prev[c, 1], prev[c, 2] = x, y, z
        else:
            prev[c, 0], prev[c, 1], prev[c, 2] = pose[c, 0], pose[c, 1], pose[c, 2]
        pose[c, 0], pose[c, 1], pose[c, 2] = x, y, z
        live[c] = 1
        ux = (x - prev[c, 0]) / dt_s
        uy = (y - prev[c, 1]) / dt_s
        uz = (z - prev[c, 2]) / dt_s
        tr[T_ACTIVE] = 1.0
        tr[T_IX], tr[T_IY], tr[T_DEPTH] = x, y, -z
        span = reach[c] + ops.margin
        c0 = max(0, int(math.floor((x - span + half_w) / spacing)))
        c1 = min(cols - 1, int(math.ceil((x + span + half_w) / spacing)))
        r0 = max(0, int(math.floor((half_h - y - span) / spacing)))
        r1 = min(rows - 1, int(math.ceil((half_h - y + span) / spacing)))
        mu_s, mu_k = mu[c, 0], mu[c, 1]
        n_sum = fx_sum = fy_sum = cx = cy = slip_w = slip_v = 0.0
        count = slipping = 0
        for r in range(r0, r1 + 1):
            for col in range(c0, c1 + 1):
                n = r * cols + col
                j = index[n]
                if j < 0:
                    continue
                st = nodes[c, n] if stamp[c, n] == now - 1 else 0
                nodes[c, n] = 0
                px = rest_xy[n, 0] + q[0, j]
                py = rest_xy[n, 1] + q[1, j]
                dx = px - x
                dy = py - y
                h = surface_height(shapes[c], geos[c], dx, dy)
                if h < 0.0:
                    continue
                pen = q[2, j] - (z + h)
                if pen <= 0.0:
                    continue
                nf = kn * pen + cn * (v[2, j] - uz)
                if nf <= 0.0:
                    continue
                if st == 0:
                    anchor[c, n, 0] = dx
                    anchor[c, n, 1] = dy
                    st = STICK
                rvx = v[0, j] - ux
                rvy = v[1, j] - uy
                fx = -kt * (dx - anchor[c, n, 0])  # the stick spring
                fy = -kt * (dy - anchor[c, n, 1])
                mag = math.sqrt(fx * fx + fy * fy)
                limit = (mu_s if st == STICK else mu_k) * nf
                if mag > limit or limit <= 0.0:
                    st = SLIP
                    scale = mu_k * nf / mag if mag > 0.0 else 0.0
                    fx *= scale
                    fy *= scale
                    anchor[c, n, 0] = dx + fx / kt
                    anchor[c, n, 1] = dy + fy / kt
                    slipping += 1
                    slip_w += nf
                    slip_v += nf * math.sqrt(rvx * rvx + rvy * rvy)
                else:
                    st = STICK
                    fx -= ct * rvx
                    fy -= ct * rvy
                    mag = math.sqrt(fx * fx + fy * fy)
                    if mag > mu_s * nf:  # the damper never pulls past the static limit
                        scale = mu_s * nf / mag
                        fx *= scale
                        fy *= scale
                nodes[c, n] = st
                stamp[c, n] = now
                out[0, j] += fx
                out[1, j] += fy
                out[2, j] -= nf
                count += 1
                n_sum += nf
                fx_sum += fx
                fy_sum += fy
                cx += nf * px
                cy += nf * py
        meas[c, 0], meas[c, 1], meas[c, 2] = fx_sum, fy_sum, n_sum
        tr[T_NODES] = count
        tr[T_AREA] = count * spacing * spacing
        tr[T_NORMAL] = n_sum
        tr[T_FX], tr[T_FY] = fx_sum, fy_sum
        if count:
            tr[T_X], tr[T_Y] = cx / n_sum, cy / n_sum
            tr[T_SLIP] = 1.0 if slipping == 0 else (3.0 if slipping == count else 2.0)
        if slipping:
            tr[T_SLIP_SPEED] = slip_v / slip_w

"""What touches the skin: contacts (an indenter on a trajectory with its friction) in scene
time, and the world's packed operands and state that the compiled step reads and updates."""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Real
from typing import ClassVar

import numpy as np

from skinhil.errors import ConfigError
from skinhil.validation import Constraints, Interval, check_param, non_negative, validate_params
from skinhil.world.contact import ContactOperands, ContactParams, ContactState
from skinhil.world.indenters import Indenter
from skinhil.world.trajectory import AXES, Trajectory

MAX_CONTACTS = 64
"""Most contacts in one scene."""
MAX_MU = 5.0
"""Largest friction coefficient."""
_MU = Interval(Real, 0, MAX_MU, closed="both", unit="friction coefficient")


@dataclass(frozen=True)
class Contact:
    """An indenter on a trajectory from ``start_s`` (s, scene time), with Coulomb friction of
    static and kinetic coefficients ``mu_static`` >= ``mu_kinetic`` >= 0."""

    indenter: Indenter
    trajectory: Trajectory
    start_s: float = 0.0
    mu_static: float = 0.8
    mu_kinetic: float = 0.6
    name: str = "contact"

    _parameter_constraints: ClassVar[Constraints] = {
        "start_s": non_negative("s"),
        "mu_static": _MU,
        "mu_kinetic": _MU,
    }

    def __post_init__(self) -> None:
        validate_params(self, where=f"contact {self.name!r}: ")
        if self.mu_kinetic > self.mu_static:
            raise ConfigError(f"contact {self.name!r}: friction needs mu_kinetic <= "
                              f"mu_static, got {self.mu_kinetic!r} > {self.mu_static!r}: "
                              "lower mu_kinetic or raise mu_static")

    @property
    def end_s(self) -> float:
        """Scene time (s) at which the contact ends."""
        return self.start_s + self.trajectory.duration_s


@dataclass(frozen=True)
class Scene:
    """The contacts of a scenario (scene time 0 where the scenario starts)."""

    contacts: tuple[Contact, ...]

    def __post_init__(self) -> None:
        if not 1 <= len(self.contacts) <= MAX_CONTACTS:
            raise ConfigError(f"a scene holds 1..{MAX_CONTACTS} contacts, got "
                              f"{len(self.contacts)}")

    @property
    def duration_s(self) -> float:
        """Scene time (s) at which the last contact ends."""
        return max(c.end_s for c in self.contacts)


class World:
    """A scene on a skin: the operands the compiled contact step reads (:attr:`operands`)
    and its state (:attr:`state`), updated in place.

    ``index`` maps each top-layer mass (row-major) to its column in the stepper's state
    arrays (-1 for a fixed mass); ``rest_xy`` (n_top, 2) m are their rest positions."""

    def __init__(self, scene: Scene, index: np.ndarray, rest_xy: np.ndarray,
                 size: tuple[int, int], spacing_m: float, params: ContactParams) -> None:
        self.scene = scene
        self.params = params
        cs = scene.contacts
        keys = [c.trajectory.keyframes for c in cs]
        ptr = np.concatenate([[0], np.cumsum([len(k) for k in keys])]).astype(np.int64)
        t = [c.trajectory for c in cs]
        self.operands = ContactOperands(
            columns=np.ascontiguousarray(index, dtype=np.int64),
            rest_xy=np.ascontiguousarray(rest_xy, dtype=np.float64),
            rows=int(size[0]), cols=int(size[1]), spacing=float(spacing_m),
            kn=float(params.normal_stiffness_n_per_m), cn=float(params.normal_damping_n_s_per_m),
            kt=float(params.tangential_stiffness_n_per_m),
            ct=float(params.tangential_damping_n_s_per_m),
            bn=float(params.admittance_m_per_n_s),
            bt=float(params.tangential_admittance_m_per_n_s), margin=float(params.margin_m),
            shapes=np.array([c.indenter.code for c in cs], dtype=np.int64),
            geos=np.stack([c.indenter.geometry() for c in cs]),
            reach=np.array([c.indenter.reach_m for c in cs]),
            starts=np.array([c.start_s for c in cs]), key_ptr=ptr, keys=np.concatenate(keys),
            control=np.array([[x.normal == "force", x.tangential == "force"] for x in t],
                             dtype=np.int64),
            vib=np.array([[x.vibration_amplitude_m, x.vibration_frequency_hz,
                           AXES.index(x.vibration_axis)] for x in t]),
            mu=np.array([[c.mu_static, c.mu_kinetic] for c in cs]),
            origin=np.array([x.origin_m for x in t], dtype=np.float64))
        """What the compiled contact step reads (:class:`ContactOperands`)."""
        n, n_top = len(cs), len(index)
        self.state = ContactState(
            pose=np.zeros((n, 3)), prev=np.zeros((n, 3)), meas=np.zeros((n, 3)),
            live=np.zeros(n, dtype=np.int64), setpoint=np.full(n, np.nan),
            nodes=np.zeros((n, n_top), dtype=np.int8), anchor=np.zeros((n, n_top, 2)),
            stamp=np.full((n, n_top), -10, dtype=np.int64), counter=np.zeros(1, dtype=np.int64))
        """What the compiled contact step updates in place (:class:`ContactState`)."""
        self.kernel_tuple = (tuple(self.operands), tuple(self.state))
        """:attr:`operands` and :attr:`state` as the kernels called from Python take them
        (:meth:`~skinhil.model.neurons.NeuronPopulation.kernel_operands` says why)."""

    def reset(self) -> None:
        """Nothing touching, set-points cleared."""
        st = self.state
        for a in (st.pose, st.prev, st.meas, st.live, st.nodes, st.anchor, st.counter):
            a[...] = 0
        st.setpoint[:] = np.nan
        st.stamp[:] = -10

    def set_load(self, contact: int, load_n: float | None) -> None:
        """Replace a force-controlled contact's load (N) from the next step on (a grip
        set-point); None returns it to its trajectory's."""
        if not 0 <= contact < len(self.scene.contacts):
            raise ConfigError(f"no contact {contact}: the scene has "
                              f"{len(self.scene.contacts)}")
        if self.scene.contacts[contact].trajectory.normal != "force":
            raise ConfigError(f"contact {contact} is position-controlled: no load to set")
        if load_n is not None:
            check_param("load_n", load_n, non_negative("N"))
        self.state.setpoint[contact] = np.nan if load_n is None else float(load_n)

"""What an NWB file says about its session: subject, experimenter, institution, description,
keywords, session id, start time; the defaults for a simulated skin.

DANDI and nwbinspector want a subject, the people and the place, a description and keywords
in every file; skinhil's files have them whether or not the user gives them. The defaults
say only what is true: the subject is the simulated skin itself (``subject_id``
``skinhil-skin-6x6``, its description the model and size; species NCBI's "synthetic
construct", :data:`SPECIES`, since it is no animal; sex ``U``, not applicable; born when
the session started, the skin being built then), the experimenter the account that ran the
command, keywords of the field; the institution is left out unless given (nwbinspector then
suggests one, and no more).
"""

from __future__ import annotations

import datetime
import getpass
from dataclasses import dataclass, field
from typing import Any

from skinhil.model.geometry import MeshSize, format_size, spring_count

SPECIES = "http://purl.obolibrary.org/obo/NCBITaxon_32630"
"""The subject's species: NCBI Taxonomy 32630, "synthetic construct" (DANDI takes species as
a Latin name or an NCBI Taxonomy address; a simulated skin is no organism)."""

DEFAULT_KEYWORDS = ("touch", "tactile sensing", "electronic skin", "neuromorphic",
                    "spiking neurons", "Izhikevich", "simulation", "skinhil")
"""Keywords of every file unless others are given."""


def login_name() -> str:
    """The account running this process ("unknown" when the system cannot say)."""
    try:
        return getpass.getuser()
    except (KeyError, OSError):
        return "unknown"


@dataclass(frozen=True)
class NwbMetadata:
    """The session metadata of an NWB file (see the module); None fields take the default."""

    subject_id: str | None = None
    """Default ``skinhil-skin-<ROWS>x<COLS>``."""
    subject_description: str | None = None
    """Default: the simulated skin's model and size."""
    experimenter: tuple[str, ...] = ()
    """People, "Last, First" as NWB asks; default: the login name running the command."""
    institution: str | None = None
    """Left out of the file when None."""
    lab: str | None = None
    experiment_description: str | None = None
    """Default: what the command ran (given by the writer)."""
    keywords: tuple[str, ...] = field(default=DEFAULT_KEYWORDS)
    session_id: str | None = None
    """Default ``skinhil-<command>-<UTC start time, ISO basic>``."""

    def nwbfile_kwargs(self, *, command: str, size: MeshSize, start: datetime.datetime,
                       description: str, experiment: str) -> dict[str, Any]:
        """Keyword arguments of :class:`pynwb.NWBFile` for a session of ``command``
        (``simulate`` or ``listen``) on a skin of ``size`` that started at ``start`` (an
        aware datetime), the session ``description`` and the default experiment
        description ``experiment``; the subject is added by :meth:`subject`."""
        stamp = start.astimezone(datetime.UTC).strftime("%Y%m%dT%H%M%S.%fZ")
        out: dict[str, Any] = {
            "session_description": description,
            "session_start_time": start,
            "experimenter": list(self.experimenter or (login_name(),)),
            "experiment_description": self.experiment_description or experiment,
            "keywords": list(self.keywords),
            "session_id": self.session_id or f"skinhil-{command}-{stamp}",
            "source_script": f"skinhil {command}", "source_script_file_name": "skinhil",
        }
        if self.institution:
            out["institution"] = self.institution
        if self.lab:
            out["lab"] = self.lab
        return out

    def subject(self, size: MeshSize, model: str, start: datetime.datetime) -> Any:
        """The file's :class:`pynwb.file.Subject`: the simulated skin of ``size`` whose
        model is described by ``model``, built at ``start``."""
        from pynwb.file import Subject

        return Subject(
            subject_id=self.subject_id or f"skinhil-skin-{format_size(size)}",
            species=SPECIES, sex="U", date_of_birth=start,
            description=self.subject_description or (
                f"simulated electronic skin (not an animal): {model}; top layer "
                f"{format_size(size)} masses, {spring_count(size)} sensors"))

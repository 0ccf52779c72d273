"""Building blocks shared by the schemas: the frozen base model, SI quantities, provenance."""

from __future__ import annotations

import re
from collections.abc import Callable
from enum import StrEnum
from typing import Annotated

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

#: A strictly positive length in metres.
Length = Annotated[float, Field(gt=0, allow_inf_nan=False)]
#: A length in metres that may be zero.
NonNegLength = Annotated[float, Field(ge=0, allow_inf_nan=False)]
#: A strictly positive mass in kilograms.
Mass = Annotated[float, Field(gt=0, allow_inf_nan=False)]
#: A finite real number (any unit; the field's doc says which).
Real = Annotated[float, Field(allow_inf_nan=False)]
#: A point or vector in metres (x, y, z).
Vec3 = tuple[Real, Real, Real]
#: A unit quaternion (w, x, y, z), MuJoCo's order.
Quat = tuple[Real, Real, Real, Real]
#: A fraction in [0, 1].
Unit = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
#: A catalog id: lower-case words joined by '-', '_', '.', grouped by '/' (for example ``two_point/bow-128``).
CatalogId = Annotated[str, Field(pattern=r"^[a-z0-9][a-z0-9_.\-]*(/[a-z0-9][a-z0-9_.\-]*)*$", max_length=120)]
SIMPLE_ID = r"^[a-z0-9][a-z0-9_.\-]*$"
"""A catalog id without '/' (a preset or a front): one component of variant and episode ids. The catalog's checks
also refuse '__' in them (:mod:`rik.registry.checks`)."""
PATH_COMPONENT = r"^[A-Za-z0-9][A-Za-z0-9_.\-]*$"
"""One component of a path that rik builds from data it reads (an episode or variant id): letters, digits, '_', '.'
and '-', not starting with '.', so it can never climb out of its folder ('..'), be absolute, hidden or empty."""


def _matches(pattern: str, what: str) -> Callable[[str], str]:
    compiled = re.compile(pattern)

    def check(value: str) -> str:
        if not compiled.fullmatch(value) or len(value) > 255:
            raise ValueError(f"{value!r} is not {what}")
        return value

    return check


#: A preset or front id (see :data:`SIMPLE_ID`).
SimpleId = Annotated[str, AfterValidator(_matches(
    SIMPLE_ID, "a simple id (lower-case letters, digits, '_', '.', '-'; no '/')"))]
#: An id that becomes a folder name (see :data:`PATH_COMPONENT`).
PathComponent = Annotated[str, AfterValidator(_matches(
    PATH_COMPONENT, "a safe folder name (letters, digits, '_', '.', '-'; not starting with '.'; no '/')"))]


class FieldError(ValueError):
    """A model validator's complaint about one field below its model: ``loc`` is that field's path from the model
    (``("mount", "home", 3)``), so that the catalog's message names the field and its line, not only the entry
    (:func:`rik.registry.entries.parse_entry` appends it to pydantic's location)."""

    def __init__(self, loc: tuple[str | int, ...], message: str) -> None:
        super().__init__(message)
        self.loc = loc


class Frozen(BaseModel):
    """Base of every catalog model: immutable, unknown fields rejected, schema built on first use."""

    model_config = ConfigDict(frozen=True, extra="forbid", defer_build=True)


class MeshFile(Frozen):
    """A user's mesh file that rik reads instead of generating geometry (written by ``rik assets import``)."""

    file: str = Field(min_length=1)
    """Path of the mesh file (STL, OBJ, PLY, GLB) relative to the YAML file that names it; metres."""
    sha256: str = Field(pattern=r"^[0-9a-f]{64}$")
    """sha256 of the file: part of the asset's cache key, and checked when the file is read."""


class Provenance(StrEnum):
    """Where a physical value comes from."""

    paper = "paper"  #: stated in the Real-IKEA paper
    literature = "literature"  #: a published or manufacturer figure
    assumed = "assumed"  #: an engineering assumption, written down in the entry's notes
    measured = "measured"  #: fitted to measured data (``rik sysid``)

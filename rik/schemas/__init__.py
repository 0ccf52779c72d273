"""Typed, frozen models of everything in the catalog. Importing this package imports pydantic only."""

from rik.schemas.base_units import BaseUnit, Carcass, DrawerBox, Front, MountSite, Placement
from rik.schemas.common import Provenance
from rik.schemas.finishes import Finish
from rik.schemas.generators import GeneratorSpec
from rik.schemas.handles import Clearance, DesignProvenance, Handle, HandleDesign, HandleGeometry, HandleType, Mount
from rik.schemas.joints import JointEffect, JointResistance, JointSpec, JointType, ResistancePreset, Spring

__all__ = [
    "BaseUnit", "Carcass", "Clearance", "DesignProvenance", "DrawerBox", "Finish", "Front", "GeneratorSpec",
    "Handle", "HandleDesign", "HandleGeometry", "HandleType", "JointEffect", "JointResistance", "JointSpec",
    "JointType", "Mount", "MountSite", "Placement", "Provenance", "ResistancePreset", "Spring",
]

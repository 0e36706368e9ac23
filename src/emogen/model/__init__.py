"""The face: mesh, blendshape deltas, identities, rig and regions."""

from emogen.model.face import FaceModel
from emogen.model.load import load_model
from emogen.model.regions import Region
from emogen.model.rig import Rig
from emogen.model.rig_build import load_rig

__all__ = ["FaceModel", "Region", "Rig", "load_model", "load_rig"]

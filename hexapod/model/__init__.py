"""The assembled model (layer 2): ``assemble(scene) -> Model``, frozen index maps and named CasADi
Functions built once and only for what the scene has; ``Model.create_data()`` gives the workspace
the algorithms fill."""

from hexapod.model.assemble import assemble
from hexapod.model.data import Data
from hexapod.model.infos import GROUND_INDEX, BodyInfo, DriverInfo, ForceInfo, JointInfo, RowInfo
from hexapod.model.model import Model

__all__ = ["GROUND_INDEX", "BodyInfo", "Data", "DriverInfo", "ForceInfo", "JointInfo", "Model",
           "RowInfo", "assemble"]

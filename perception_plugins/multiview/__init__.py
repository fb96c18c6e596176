"""Multi-view object models and three-stage recognition (seed 000 §3.1–3.2).

A model is built from several views of an overview run (`formation.build_model`): points, 3D segment lines with
their face side, and corners, per view in its camera frame, with the object frame built on a base segment
(Figure 2) and the full model averaged over the views (`model`); it is read and written by `model_io`. A working
stereo pair is recognised in three stages (`recognition.recognise`: points → lines and corners → the refined
transform by approach 1, 2(a), 2(b) or 3), with the seed's recognition table and an identification decision.

Pure numpy + OpenCV; it imports `perception_plugins.stereo` and `perception_plugins.referencing`, nothing of
`mission` but its plug-in contract.
"""

from perception_plugins.multiview.edits import Edits, parse_edits, read_edits
from perception_plugins.multiview.errors import MultiviewError
from perception_plugins.multiview.formation import FormationSettings, ViewInput, build_model, extend_model
from perception_plugins.multiview.model import ObjectModel, ViewModel
from perception_plugins.multiview.object_frame import object_frame
from perception_plugins.multiview.recognition import (
    APPROACHES,
    Recognition,
    RecognitionSettings,
    choose_views,
    recognise,
)

__all__ = ["APPROACHES", "Edits", "FormationSettings", "MultiviewError", "ObjectModel", "Recognition",
           "RecognitionSettings", "ViewInput", "ViewModel", "build_model", "choose_views", "extend_model",
           "object_frame", "parse_edits", "read_edits", "recognise"]

"""The interactive viewer: the seed demo as a program, and BoxToss played by hand.

``python -m box_toss_env.viewer`` opens a named scene (the seed demo by default) with the demo's
read-outs and controls; ``--play`` throws BoxToss's box by dragging; ``--frames N --out PATH``
draws frames to PNG without a window. See ``python -m box_toss_env.viewer --help``.

- ``controller``: the viewer's model (scenes, parameters, stepping, dragging, zoom), pure numpy;
- ``play``: play mode's model (drag -> the env's action, the env's reward), pure numpy;
- ``window``: the pygame front end of both, imported only when something is drawn.
"""

from box_toss_env.viewer.controller import PARAMETERS, ROWS, STEPS_PER_FRAME, Lane, StepTimer, ViewerController
from box_toss_env.viewer.play import THROW_GAIN, PlayController, ThrowResult, throw_to_action

__all__ = [
    "PARAMETERS",
    "ROWS",
    "STEPS_PER_FRAME",
    "THROW_GAIN",
    "Lane",
    "PlayController",
    "StepTimer",
    "ThrowResult",
    "ViewerController",
    "throw_to_action",
]

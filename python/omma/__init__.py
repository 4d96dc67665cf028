"""omma: compound-eye camera toolkit -- rigs, dome design, simulator, stitcher, real-time engine, calibration,
recordings, offline rendering, the live engine and the recording planner.

Images are NumPy arrays in OpenCV's layout and channel order: (H, W, 3) BGR, uint8 (or uint16,
float32 in [0, 1] where a function says so: values outside warn, NaN raises). Frames are one image per
rig camera, in rig order, as a list or one (N, H, W, 3) array. Errors raise omma.Error subclasses
(RigError, IoError, SceneError, SinkError, RecordingError, PtoError, SourceError) or
ValueError/TypeError with the messages the `omma` command prints.

    import omma
    rig = omma.Rig.load("thesis-24")                                     # a file or a built-in name
    sim = omma.simulate(rig, scene="checker", size=(540, 540))
    pano = omma.stitch(rig, sim.frames, method="mrf", size=(540, 540))   # float32 reference
    engine = omma.Engine(rig, method="mrf", size=(540, 540))
    fast = engine.render(sim.frames)                                     # uint8, real time
    print(omma.evaluate(fast, sim.truth))
    for pano in omma.run(rig, source="sim:colon", frames=10, sinks=["out.mp4"]):
        ...                                                              # the live engine

Every function and method has a real Python signature (inspect.signature, help()) and type stubs
(__init__.pyi, PEP 561).
"""
from . import _omma
from ._signatures import wrap_module as _wrap_module

_wrap_module(_omma, globals())

from ._omma import (CalibrationOptions, CameraEffects, Design, Engine, Error, FrameSet, IoError,  # noqa: E402,F401
                    LiveRun, METHODS, PROJECTIONS, PtoError, Recording, RecordingError, Rig, RigError,
                    SceneError, Simulation, SinkError, SourceError)
from ._omma import __version__  # noqa: E402,F401  (the file VERSION, through the C++ library)

open_recording = Recording  # open_recording(path) is Recording(path)


def _iter_frame_sets(self):
    """The recording's frame sets in order (raw frames; frame_set(i, develop=True) develops them)."""
    for i in range(len(self)):
        yield self[i]


Recording.__iter__ = _iter_frame_sets

__all__ = sorted(k for k in globals() if not k.startswith("_"))

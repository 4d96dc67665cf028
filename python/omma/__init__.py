"""omma: compound-eye camera toolkit -- rigs, dome design, simulator, stitcher, real-time engine, calibration.

Images are NumPy arrays in OpenCV's layout and channel order: (H, W, 3) BGR, uint8 (or uint16,
float32 in [0, 1] where a function says so). Frames are one image per rig camera, in rig order, as a
list or one (N, H, W, 3) array. Errors raise omma.Error subclasses (RigError, IoError, SceneError)
or ValueError/TypeError with the messages the `omma` command prints.

    import omma
    rig = omma.thesis_prototype_rig()
    sim = omma.simulate(rig, scene="checker", size=(540, 540))
    pano = omma.stitch(rig, sim.frames, method="mrf", size=(540, 540))   # float32 reference
    engine = omma.Engine(rig, method="mrf", size=(540, 540))
    fast = engine.render(sim.frames)                                     # uint8, real time
    print(omma.evaluate(fast, sim.truth))
"""
from ._omma import *  # noqa: F401,F403
from ._omma import (CalibrationOptions, CameraEffects, Design, Engine, Error, IoError, METHODS,  # noqa: F401
                    PROJECTIONS, Rig, RigError, SceneError, Simulation, SinkError)

from ._omma import __version__  # noqa: F401  (the file VERSION, through the C++ library)

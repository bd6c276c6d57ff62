"""Client for the URLab simulation runtime.

The streaming topics of protocol.md: discovery of every robot's actuators, decoded state as
numpy arrays keyed by name, and control by actuator name or id.

    from urlab_client import StreamClient
    client = StreamClient("127.0.0.1")
    robots = client.discover()              # {"arm": Robot(...)}
    client.send_control("arm", {"shoulder_motor": 0.3})
    state = client.poll()                    # {"arm": {"joint": {...}, "sensor": {...}}}

camera streams (numpy images from discovery's camera_list):

    from urlab_client import CameraClient
    image, meta = CameraClient(robots["arm"].cameras[0]).receive()

and the step server (lockstep learning loops):

    from urlab_client import UrlabEnv
    env = UrlabEnv("arm")                    # tcp://127.0.0.1:5559, direct mode
    obs = env.reset()
    obs, info = env.step([0.1, -0.2])
"""
from urlab_client.camera import CameraClient, decode_frame
from urlab_client.step import StepClient, UrlabEnv, UrlabError
from urlab_client.stream import Robot, StreamClient
from urlab_client import wire

__all__ = ["CameraClient", "decode_frame", "Robot", "StepClient", "StreamClient", "UrlabEnv", "UrlabError", "wire"]
__version__ = "0.1.0"

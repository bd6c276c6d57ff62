"""Client for the URLab simulation runtime.

The streaming topics of docs/protocol.md: discovery of every robot's actuators, decoded state as
numpy arrays keyed by name, and control by actuator name or id.

    from urlab_client import StreamClient
    client = StreamClient("127.0.0.1")
    robots = client.discover()              # {"arm": Robot(...)}
    client.send_control("arm", {"shoulder_motor": 0.3})
    state = client.poll()                    # {"arm": {"joint": {...}, "sensor": {...}}}

camera streams (numpy images from discovery's camera_list):

    from urlab_client import CameraClient
    image, meta = CameraClient(robots["arm"].cameras[0]).receive()

and the step server (lockstep learning loops) as gymnasium environments:

    from urlab_client import UrlabEnv
    with UrlabEnv("arm", max_episode_steps=100) as env:   # tcp://127.0.0.1:5559, direct mode
        obs, info = env.reset(seed=0)
        obs, reward, terminated, truncated, info = env.step([0.1, -0.2])

UrlabVectorEnv steps many servers together (urlab_client.vector), the environments of batched
servers (urlab_client.batch), or a batch inside this process with no server
(UrlabVectorEnv.in_process, urlab_client.inproc); urlab_client.cluster starts servers on a Dask
cluster and returns one; urlab_client.rollout runs in-process batches as Dask rollout workers.

Importing the package registers the bundled tasks (urlab_client.tasks) with gymnasium (a
dependency of the package; without it, the streaming and step clients still work under Debian's
python3, and the environments raise ImportError when asked for):

    import gymnasium
    env = gymnasium.make("URLab/ArmReach-v0")                        # its own urlab server
    envs = gymnasium.make_vec("URLab/ArmReach-v0", num_envs=16,
                              vectorization_mode="vector_entry_point")  # in this process
"""
from urlab_client.camera import CameraClient, decode_frame
from urlab_client.step import StepClient, UrlabError
from urlab_client.stream import Robot, StreamClient
from urlab_client import wire

try:
    import gymnasium as _gymnasium  # noqa: F401
except ImportError as _missing:  # Debian's python3 alone: no environments, the clients work
    _GYMNASIUM_MISSING = _missing
else:
    _GYMNASIUM_MISSING = None
    from urlab_client import tasks
    tasks.register()

_ENVIRONMENTS = {"UrlabEnv": "urlab_client.env", "UrlabVectorEnv": "urlab_client.vector"}


def __getattr__(name):
    """UrlabEnv and UrlabVectorEnv, imported when first asked for (they need gymnasium)."""
    if name in _ENVIRONMENTS:
        if _GYMNASIUM_MISSING is not None:
            raise ImportError(f"urlab_client.{name} needs gymnasium ({_GYMNASIUM_MISSING}): "
                              "install the client with pip (`.venv/bin/pip install -e "
                              "clients/python`) or run the project's .venv/bin/python")
        import importlib
        value = getattr(importlib.import_module(_ENVIRONMENTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'urlab_client' has no attribute {name!r}")


__all__ = ["CameraClient", "decode_frame", "Robot", "StepClient", "StreamClient", "UrlabEnv",
           "UrlabError", "UrlabVectorEnv", "wire"]
__version__ = "0.1.0"

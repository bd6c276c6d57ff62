"""Camera streams (docs/protocol.md "Camera frames out"): one PUB per stream, raw pixels.

Each entry of discovery's `camera_list` (Robot.cameras) or hello's `camera_topics` describes a
stream: name, endpoint, width, height, mode, topic, meta_topic. Frames decode to numpy arrays:
rgb -> H x W x 3 uint8 (RGB), depth -> H x W float32 metres, segmentation / instance -> H x W
int32 ids (-1: background; geom ids, or articulation indices; `ids` in the entry names them).

    cam = CameraClient(robots["arm"].cameras[0])
    image, meta = cam.receive(timeout=1.0)   # meta: frame_id, step, sim_time, ..., received_ns
"""
import json
import time

import numpy as np
import zmq


def decode_frame(payload, mode, width, height):
    """The wire bytes of one frame as a numpy array (see the module's docstring)."""
    if mode == "depth":
        return np.frombuffer(payload, dtype="<f4").reshape(height, width)
    bgra = np.frombuffer(payload, dtype=np.uint8).reshape(height, width, 4)
    if mode == "rgb":
        return bgra[:, :, 2::-1].copy()
    ids = bgra[:, :, 0].astype(np.int32) | (bgra[:, :, 1].astype(np.int32) << 8) | \
        (bgra[:, :, 2].astype(np.int32) << 16)
    return ids - 1


class CameraClient:
    """Subscribes to one camera stream (and its meta topic)."""

    def __init__(self, entry, context=None, host=None):
        self.entry = dict(entry)
        self.name, self.mode = entry["name"], entry["mode"]
        self.width, self.height = int(entry["width"]), int(entry["height"])
        self.topic = entry.get("topic", "").encode()
        self.meta_topic = entry.get("meta_topic", "").encode()
        endpoint = entry["endpoint"]
        if host:
            endpoint = endpoint.replace("127.0.0.1", host)
        self._ctx = context or zmq.Context.instance()
        self._socket = self._ctx.socket(zmq.SUB)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.setsockopt(zmq.RCVHWM, 4)
        self._socket.setsockopt(zmq.SUBSCRIBE, self.topic)
        if self.meta_topic:
            self._socket.setsockopt(zmq.SUBSCRIBE, self.meta_topic)
        self._socket.connect(endpoint)
        self._meta = None

    def close(self):
        self._socket.close(0)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def receive(self, timeout=1.0):
        """The next frame as (array, meta); meta is None when its meta message was missed.
        Raises TimeoutError when no frame arrives in `timeout` seconds."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not self._socket.poll(int(left * 1000)):
                raise TimeoutError(f"no frame from camera stream '{self.name}' in {timeout} s")
            topic, payload = self._socket.recv_multipart()
            received = time.time_ns()
            if topic == self.meta_topic:
                self._meta = json.loads(payload)
                continue
            meta, self._meta = self._meta, None
            if meta is not None:
                meta["received_ns"] = received
            return decode_frame(payload, self.mode, self.width, self.height), meta

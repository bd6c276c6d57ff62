"""A step-server connection spoken by hand, as the plugin's 2026 client speaks it (the end-to-end
tests of that dialect): one ZeroMQ REQ socket, msgpack, the session id in every request after
hello, requests numbered by `seq` when asked (the reply must echo it)."""
import msgpack
import zmq


class Refused(Exception):
    """An error reply: `code` and `message` as the server sent them."""

    def __init__(self, code, message):
        super().__init__(f"{code}: {message}")
        self.code, self.message = code, message


class StepSocket:
    """`on_failure(message)` is called when a reply does not echo its request's `seq`."""

    def __init__(self, endpoint, ctx, on_failure, number_requests=False):
        self.sock = ctx.socket(zmq.REQ)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.setsockopt(zmq.RCVTIMEO, 30000)
        self.sock.connect(endpoint)
        self.session_id = None
        self.seq = 0
        self.on_failure = on_failure
        self.number_requests = number_requests

    def call(self, op, **fields):
        request = {"op": op, **fields}
        if self.number_requests:
            self.seq += 1
            request["seq"] = self.seq
        if self.session_id:
            request["session_id"] = self.session_id
        self.sock.send(msgpack.packb(request, use_bin_type=True))
        reply = msgpack.unpackb(self.sock.recv(), raw=False)
        if reply.get("op") == "error":
            raise Refused(reply.get("code"), reply.get("message", ""))
        if self.number_requests and reply.get("seq") != self.seq:
            self.on_failure(f"{op}: seq {reply.get('seq')} for {self.seq}")
        return reply

    def hello(self, **fields):
        reply = self.call("hello", **fields)
        self.session_id = reply["session_id"]
        return reply

    def close(self):
        self.sock.close(0)


def refused(code, on_failure, fn, *args, **kwargs):
    """Calls fn(*args, **kwargs), which must be refused with `code`; returns the Refused."""
    try:
        fn(*args, **kwargs)
    except Refused as e:
        if e.code != code:
            on_failure(f"refused with {e.code} ({e.message}), want {code}")
        return e
    on_failure(f"accepted, want {code}")

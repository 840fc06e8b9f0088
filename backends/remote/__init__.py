"""A robot backend over TCP: the world's process serves, an agent process calls.

Entry point ``rll_bt.backends: remote`` -> :class:`RemoteBackend`::

    rll-bt agent --backend remote --backend-opt address=127.0.0.1:4470 --backend-opt robot=2 ...

The serving end, for a process that holds robots (a simulated world)::

    server = RemoteBackend.serve(lambda team, number: backends[number], clock.now)   # port 0: see server.port
    while ...:
        server.poll(0.005)             # answers what arrived, then returns: the world keeps time

Wire (:mod:`rll_bt.comm.jsonlink`): each message is a 4-byte big-endian
length and a UTF-8 JSON object.  A request ``{"id", "robot": [team,
number], "m": method, "a": [args]}`` gets ``{"id", "r": result, "now":
server time}`` or ``{"id", "e": error class name, "msg": text}``.  Values
cross as :mod:`.codec` writes them.  Stamps are moved onto the client's
clock: the offset between the server's time and the client's
``clock.now()`` is taken at the first reply.

- :mod:`.client`: :class:`RemoteBackend`, the calling end;
- :mod:`.server`: :class:`BackendServer`, answering for any
  :class:`~rll_bt.backend.Backend` objects (``resolve(team, number)``);
- :mod:`.codec`: the backend's values as JSON and back.
"""
from .client import RemoteBackend
from .codec import METHODS, decode, encode
from .server import BackendServer

__all__ = ["RemoteBackend", "BackendServer", "METHODS", "encode", "decode"]

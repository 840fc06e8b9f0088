"""The refbox wire protocol (protobuf_comm) and the transports that carry it.

- :mod:`.framing`: frame header v2 (and v1, decode only), message header,
  stream reassembly.
- :mod:`.crypto`: cipher ids 0..4, the refbox's key derivation, AES-ECB/CBC.
- :mod:`.registry`: message classes keyed by their ``CompType``.
- :mod:`.codec`: message <-> frame with optional crypto; counts drops.
- :mod:`.udp`, :mod:`.tcp`, :mod:`.bus`: transports with one interface
  (:class:`~.transport.Transport`): ``send(msg)``, ``receive()``,
  ``events()``, ``wait(timeout)``, ``close()``, ``stats``.
- :mod:`.ports`: the competition and sim port layouts, :func:`free_ports`.
- :mod:`.msglog`: a message log (decoded frames as JSON lines).
- :mod:`.jsonlink`: framed JSON request/reply links between processes.
"""
from .bus import Bus, BusPeer, BusStreamClient, BusStreamServer
from .codec import Decoded, FrameCodec
from .crypto import (
                     AES_128_CBC,
                     AES_128_ECB,
                     AES_256_CBC,
                     AES_256_ECB,
                     CIPHERS,
                     NONE,
                     TEAM_CIPHER,
                     FrameCrypto,
                     cipher_id,
                     derive_key,
)
from .errors import CommError, CryptoError, FrameTooLarge, NoCompType, RegistryConflict
from .framing import (
                     FRAME_HEADER_SIZE,
                     FRAME_V1,
                     FRAME_V2,
                     MAX_DATAGRAM,
                     MAX_STREAM_PAYLOAD,
                     MESSAGE_HEADER_SIZE,
                     FrameHeader,
                     FrameHeaderV1,
                     MessageHeader,
                     StreamReassembler,
)
from .ports import (
                     CHANNELS,
                     COMPETITION,
                     CYAN,
                     DEFAULT_HOST,
                     LAYOUTS,
                     MAGENTA,
                     PUBLIC,
                     REFBOX_STREAM_PORT,
                     SIM,
                     TEAM_COLORS,
                     TEAM_SERVER_PORT,
                     Layout,
                     PeerPorts,
                     free_ports,
                     layout,
)
from .registry import MessageRegistry, comp_type_of
from .stats import CAUSES, DropStats
from .tcp import StreamClient, StreamServer
from .transport import CONNECTED, DISCONNECTED, LinkEvent, Received, Transport
from .udp import UdpPeer

__all__ = [
    "Bus", "BusPeer", "BusStreamClient", "BusStreamServer", "Decoded", "FrameCodec",
    "AES_128_CBC", "AES_128_ECB", "AES_256_CBC", "AES_256_ECB", "CIPHERS", "NONE", "TEAM_CIPHER",
    "FrameCrypto", "cipher_id", "derive_key", "CommError", "CryptoError", "FrameTooLarge",
    "NoCompType", "RegistryConflict", "FRAME_HEADER_SIZE", "FRAME_V1", "FRAME_V2",
    "MAX_DATAGRAM", "MAX_STREAM_PAYLOAD", "MESSAGE_HEADER_SIZE", "FrameHeader", "FrameHeaderV1",
    "MessageHeader", "StreamReassembler", "CHANNELS", "COMPETITION", "CYAN", "DEFAULT_HOST",
    "LAYOUTS", "MAGENTA", "PUBLIC", "REFBOX_STREAM_PORT", "SIM", "TEAM_COLORS",
    "TEAM_SERVER_PORT", "Layout", "PeerPorts", "free_ports", "layout", "MessageRegistry", "comp_type_of",
    "CAUSES", "DropStats", "StreamClient", "StreamServer", "CONNECTED", "DISCONNECTED",
    "LinkEvent", "Received", "Transport", "UdpPeer",
]

"""The refbox's stored games for tests: game report documents with the
refbox's key names, written in MongoDB's archive format (what ``mongodump
--archive --gzip`` writes, as the refbox's ``benchmarks/rcll100.gz``)."""
from __future__ import annotations

import gzip
import struct

import bson

MAGIC = struct.pack("<I", 0x8199E26D)
END = struct.pack("<i", -1)


def report(name, rs1_zone="C_Z63", rs1_rot=90):
    """A game report document as the refbox stores it (only the keys a stored game uses, and a few more)."""
    machines = [
        {"name": "C-BS", "team": "CYAN", "mtype": "BS", "zone": "C_Z44", "rotation": 90, "down-period": [-1.0, -1.0]},
        {"name": "C-RS1", "team": "CYAN", "mtype": "RS", "zone": rs1_zone, "rotation": rs1_rot,
         "down-period": [300.0, 345.0], "rs-ring-colors": ["RING_BLUE", "RING_GREEN"]},
        {"name": "M-RS1", "team": "MAGENTA", "mtype": "RS", "zone": "M_Z63", "rotation": 90,
         "down-period": [300.0, 345.0], "rs-ring-colors": ["RING_BLUE", "RING_GREEN"]},
    ]
    orders = [
        {"id": 1, "complexity": "C0", "competitive": "FALSE", "base-color": "BASE_SILVER", "ring-colors": [],
         "cap-color": "CAP_GREY", "quantity-requested": 1, "quantity-delivered": [0, 0],
         "delivery-period": [0, 1020], "delivery-gate": 2, "active": "TRUE", "activate-at": 0},
        {"id": 6, "complexity": "C2", "competitive": "TRUE", "base-color": "BASE_RED",
         "ring-colors": ["RING_BLUE", "RING_GREEN"], "cap-color": "CAP_BLACK", "quantity-requested": 1,
         "quantity-delivered": [0, 0], "delivery-period": [401, 574], "delivery-gate": 3, "active": "FALSE",
         "activate-at": 172},
    ]
    return {"report-name": name, "machines": machines, "orders": orders, "teams": ["Carologistics", ""],
            "ring-specs": [{"color": "RING_GREEN", "req-bases": 2}, {"color": "RING_BLUE", "req-bases": 1},
                           {"color": "RING_ORANGE", "req-bases": 0}, {"color": "RING_YELLOW", "req-bases": 0}]}


def archive(docs, zipped=True):
    """MongoDB's archive format: magic, header, collection metadata, a block of documents, EOF block."""
    ns = {"db": "rcll", "collection": "game_report"}
    out = MAGIC + bson.encode({"concurrent_collections": 1, "version": "0.1", "server_version": "4.0.23"})
    out += bson.encode({**ns, "metadata": "{}", "size": 0}) + END
    out += bson.encode({**ns, "EOF": False, "CRC": 0}) + b"".join(bson.encode(d) for d in docs) + END
    out += bson.encode({**ns, "EOF": True, "CRC": 0})
    return gzip.compress(out) if zipped else out

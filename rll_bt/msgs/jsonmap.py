"""Messages to and from plain dicts: protobuf's JSON mapping.

Field names stay as written in the ``.proto`` (``team_cyan``, not
``teamCyan``), enums are written by name, 64-bit integers as decimal strings
(the JSON mapping's rule), and only fields that are set appear.  Parsing
accepts both the original and the camelCase names, enum names or numbers.
"""
from __future__ import annotations

from google.protobuf import json_format
from google.protobuf.message import Message


def to_dict(msg: Message) -> dict:
    """``msg`` as a dict: original field names, enums by name."""
    return json_format.MessageToDict(msg, preserving_proto_field_name=True)


def from_dict(ms, name, data: dict, *, require_initialized: bool = False) -> Message:
    """Build message ``name`` of message set ``ms`` (a :class:`MessageSet` or its name) from ``data``.

    ``name`` is a top-level message name (or a class of the set).  Unknown
    fields, wrong types and bad enum names raise ValueError naming the
    message; with ``require_initialized`` so do missing required fields.
    """
    if isinstance(ms, str):
        from .messageset import message_set
        ms = message_set(ms)
    cls = ms.get(name) if isinstance(name, str) else name
    type_name = cls.DESCRIPTOR.name
    if not isinstance(data, dict):
        raise ValueError(f"{ms.name}.{type_name}: expected a JSON object, got {type(data).__name__}")
    try:
        msg = json_format.ParseDict(data, cls())
    except json_format.ParseError as exc:
        raise ValueError(f"{ms.name}.{type_name}: {exc}") from None
    except (TypeError, AttributeError, OverflowError, RecursionError) as exc:
        # ParseDict lets a few of these through for oddly typed values.
        raise ValueError(f"{ms.name}.{type_name}: invalid value ({exc})") from None
    if require_initialized and not msg.IsInitialized():
        missing = ", ".join(msg.FindInitializationErrors())
        raise ValueError(f"{ms.name}.{type_name}: missing required field(s): {missing}")
    return msg

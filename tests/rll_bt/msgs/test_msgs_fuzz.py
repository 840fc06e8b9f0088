"""Random input to the decoders of rll_bt.msgs: only the documented errors come out."""
from __future__ import annotations

from google.protobuf.message import DecodeError
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rll_bt import msgs

NAMES = [(s, n) for s in msgs.SETS for n in msgs.message_set(s).classes]

json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2**70, 2**70) | st.floats(allow_nan=True)
    | st.text(max_size=12),
    lambda children: st.lists(children, max_size=4)
    | st.dictionaries(st.text(max_size=12), children, max_size=4),
    max_leaves=12)


def _field_keys():
    keys = set()
    for s, n in NAMES:
        keys.update(msgs.message_set(s).get(n).DESCRIPTOR.fields_by_name)
    return sorted(keys)


objects = st.dictionaries(st.sampled_from(_field_keys()) | st.text(max_size=8), json_values,
                          max_size=6)


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(which=st.sampled_from(NAMES), data=objects, strict=st.booleans())
def test_from_dict_only_raises_value_error(which, data, strict):
    set_name, name = which
    try:
        msg = msgs.from_dict(set_name, name, data, require_initialized=strict)
    except ValueError:
        return
    assert msgs.from_dict(set_name, name, msgs.to_dict(msg)) == msg


@settings(max_examples=250, deadline=None)
@given(which=st.sampled_from(NAMES), payload=st.binary(max_size=64))
def test_decode_random_payload(which, payload):
    set_name, name = which
    ms = msgs.message_set(set_name)
    comp_id, msg_type = ms.comp_type(ms.get(name))
    try:
        msg = ms.decode(comp_id, msg_type, payload)
    except DecodeError:
        return
    assert isinstance(msg, ms.get(name))

"""The generated modules are current, and the check notices when they are not."""
from __future__ import annotations

import shutil

import pytest
from google.protobuf import descriptor_pb2

from rll_bt.msgs import generate
from rll_bt.msgs.descriptors import normalise, normalise_bytes
from rll_bt.msgs.messageset import MessageSet
from rll_bt.msgs.sources import PACKAGE_DIR, SETS

pytestmark = pytest.mark.xdist_group("msgs_generate")


@pytest.fixture
def pkg_copy(tmp_path):
    """A copy of rll_bt/msgs' proto/ and _gen_*.py to break."""
    shutil.copytree(PACKAGE_DIR / "proto", tmp_path / "proto")
    for s in SETS:
        shutil.copy(PACKAGE_DIR / f"_gen_{s}.py", tmp_path / f"_gen_{s}.py")
    return tmp_path


def test_generated_modules_are_current(capsys):
    assert generate.main(["--check", "--quiet"]) == 0, capsys.readouterr().err


def test_changed_field_number_is_stale(pkg_copy, capsys):
    src = pkg_copy / "proto" / "rcll2016" / "GameState.proto"
    text = src.read_text()
    assert "optional uint32 points_cyan = 5;" in text
    src.write_text(text.replace("optional uint32 points_cyan = 5;",
                                "optional uint32 points_cyan = 7;"))
    assert generate.main(["--check", "--quiet", "--dir", str(pkg_copy)]) == 1
    err = capsys.readouterr().err
    assert "rcll2016" in err and "GameState.proto changed" in err
    assert "rcll2025" not in err and "message set team" not in err

    # regenerating repairs it, and the new module carries the change
    assert generate.main(["--quiet", "--dir", str(pkg_copy)]) == 0
    assert generate.main(["--check", "--quiet", "--dir", str(pkg_copy)]) == 0
    values = generate.read_module(pkg_copy / "_gen_rcll2016.py")
    ms = MessageSet("rcll2016", generate.embedded_descriptor_set(values))
    assert ms.GameState.DESCRIPTOR.fields_by_name["points_cyan"].number == 7


def test_comment_only_change_is_stale(pkg_copy, capsys):
    src = pkg_copy / "proto" / "team" / "task.proto"
    src.write_text(src.read_text() + "\n// a trailing comment\n")
    assert generate.main(["--check", "--quiet", "--dir", str(pkg_copy), "--set", "team"]) == 1
    assert "task.proto changed" in capsys.readouterr().err


def test_added_and_removed_files_are_stale(pkg_copy, capsys):
    (pkg_copy / "proto" / "rcll2025" / "Extra.proto").write_text(
        'syntax = "proto2";\npackage llsf_msgs;\nmessage Extra { optional uint32 a = 1; }\n')
    assert generate.main(["--check", "--quiet", "--dir", str(pkg_copy), "--set", "rcll2025"]) == 1
    assert "Extra.proto was added" in capsys.readouterr().err
    (pkg_copy / "_gen_rcll2025.py").unlink()
    assert generate.main(["--check", "--quiet", "--dir", str(pkg_copy), "--set", "rcll2025"]) == 1
    assert "_gen_rcll2025.py is missing" in capsys.readouterr().err


def test_semantic_difference_with_matching_hashes_is_stale(pkg_copy, capsys):
    """A module whose hashes match but whose descriptors do not (e.g. edited by hand)."""
    path = pkg_copy / "_gen_team.py"
    values = generate.read_module(path)
    fds = descriptor_pb2.FileDescriptorSet()
    fds.ParseFromString(generate.embedded_descriptor_set(values))
    fds.file[0].message_type[0].field[0].number = 99
    compiled = generate.Compiled("team", fds.SerializeToString(), dict(values["SOURCES"]))
    path.write_text(generate.render_module(compiled))
    assert generate.main(["--check", "--quiet", "--dir", str(pkg_copy), "--set", "team"]) == 1
    assert "descriptors differ for common.proto" in capsys.readouterr().err


def test_broken_proto_exits_2_naming_the_file(pkg_copy, capsys):
    src = pkg_copy / "proto" / "rcll2016" / "Time.proto"
    src.write_text(src.read_text().replace("required int64 nsec = 2;", "required int64 nsec = ;"))
    assert generate.main(["--check", "--quiet", "--dir", str(pkg_copy)]) == 2
    assert "Time.proto" in capsys.readouterr().err


def test_unknown_set_option_is_a_usage_error():
    with pytest.raises(SystemExit) as exc:
        generate.main(["--set", "rcll2030"])
    assert exc.value.code == 2


def test_normal_form_ignores_protoc_version_details():
    """syntax "proto2", default json_name and file order do not change the normal form."""
    values = generate.read_module(PACKAGE_DIR / "_gen_rcll2016.py")
    plain = generate.embedded_descriptor_set(values)
    fds = descriptor_pb2.FileDescriptorSet()
    fds.ParseFromString(plain)
    noisy = descriptor_pb2.FileDescriptorSet()
    for f in reversed(fds.file):
        g = noisy.file.add()
        g.CopyFrom(f)
        g.syntax = "proto2"
        for m in g.message_type:
            for field in m.field:
                field.json_name = "".join(p if i == 0 else p.capitalize()
                                          for i, p in enumerate(field.name.split("_")))
    assert noisy.SerializeToString() != plain
    assert normalise_bytes(noisy.SerializeToString()) == plain
    assert normalise(noisy) == normalise(fds)
    # an explicit, non-default json_name is kept
    noisy.file[0].message_type[0].field[0].json_name = "custom"
    assert normalise_bytes(noisy.SerializeToString()) != plain

"""Tree files never evaluate code: unsafe YAML tags and expression tricks
are refused; the loader and the expression parser only ever fail cleanly."""
from hypothesis import given, settings
from hypothesis import strategies as st

from rll_bt.tree import ExprError, parse_expr


def test_python_object_tags_are_refused(check):
    for text in ("root: !!python/object/apply:os.system ['echo pwned']\n",
                 "root:\n  log: {message: !!python/object:os.system {}}\n",
                 "root:\n  log: {message: !!python/name:os.system}\n"):
        errs = check(text)
        assert len(errs) == 1 and "python/" in errs[0] and "tags such as !!python/object are refused" in errs[0]


def test_code_in_conditions_is_refused(check):
    for cond, what in (("__import__('os')", "function calls are not allowed"),
                       ("__import__('os').system('x')", "attribute access is not allowed"),
                       ("open('/etc/passwd')", "function calls are not allowed"),
                       ("a.__class__", "attribute access is not allowed"),
                       ("[x for x in y]", "expected ']'"),
                       ("lambda: 1", "unexpected character ':'"),
                       ("__builtins__ == 1", "is not a valid blackboard key")):
        errs = check(f'root:\n  check_blackboard: {{condition: "{cond}"}}\n')
        assert len(errs) == 1 and what in errs[0], (cond, errs)


def test_only_registered_node_types(check):
    errs = check("root:\n  os.system: {cmd: ls}\n")
    assert "unknown node type 'os.system'" in errs[0]


@settings(max_examples=250, deadline=None)
@given(st.text(max_size=60))
def test_expression_parser_fails_only_with_expr_error(text):
    try:
        parse_expr(text)
    except ExprError as exc:
        assert 0 <= exc.offset <= len(text)


_yamlish = st.text(alphabet=st.sampled_from(list("root:- {}[]'\"!&*\n\t #$.,abcdwaitsequence_1")), max_size=80)


@settings(max_examples=200, deadline=None)
@given(_yamlish)
def test_loader_fails_only_with_located_errors(tmp_path_factory, text):
    from rll_bt.tree import TreeLoadError, parse_tree
    path = tmp_path_factory.mktemp("fuzz") / "t.yaml"
    path.write_text(text)
    try:
        parse_tree(path)
    except TreeLoadError as exc:
        assert exc.diagnostics and all(d.loc.line >= 1 and d.hint is not None for d in exc.diagnostics)

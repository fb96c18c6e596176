"""The bounded composer refuses the same documents on both parsers (libyaml's and PyYAML's pure-Python one), at
the node past the limit, and composes ordinary documents as PyYAML does."""

from __future__ import annotations

import pytest
import yaml

from mission.language import limits
from mission.language.composer import ExactLoader, FastLoader, LimitExceeded
from mission.language.source import parse_yaml

LOADERS = [ExactLoader] + ([FastLoader] if FastLoader is not None else [])
BOMB = "\n".join(["a0: &a0 [x, x, x, x, x, x, x, x, x]"] +
                 [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 10)])


def compose(loader: type, text: str) -> yaml.Node:
    instance = loader(text)
    try:
        return instance.get_single_node()  # type: ignore[no-any-return]
    finally:
        instance.dispose()


@pytest.mark.parametrize("loader", LOADERS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("text, problem, line", [
    (BOMB, "aliases expanded", 6),
    ("a: " + "[" * 100 + "]" * 100, "nesting deeper", 1),
    ("a: &r [b, *r]", "contains it", 1),
    ("a:\n  b: !!python/name:os.system x", "tag !!python/name:os.system", 2),
    ("a: [" + ", ".join(["&x 1"] + ["*x"] * (limits.MAX_ALIASES + 1)) + "]", "more than 100 aliases", 1),
], ids=["bomb", "nesting", "recursive", "tag", "aliases"])
def test_both_parsers_refuse_past_a_limit_at_the_offending_line(loader, text, problem, line):
    with pytest.raises(LimitExceeded) as caught:
        compose(loader, text)
    assert problem in str(caught.value.problem)
    assert caught.value.problem_mark.line + 1 == line


def test_a_mapping_of_more_than_the_entry_limit_is_refused_at_the_key_past_it():
    text = "{" + ", ".join(f"k{i}: 1" for i in range(limits.MAX_ITEMS + 1)) + "}"
    with pytest.raises(LimitExceeded) as caught:
        compose(LOADERS[-1], text)  # the fast parser when there is one: the pure-Python one takes seconds
    assert "more than 100,000 keys" in str(caught.value.problem)
    assert caught.value.problem_mark.column == text.index(f"k{limits.MAX_ITEMS}:")


@pytest.mark.parametrize("loader", LOADERS, ids=lambda c: c.__name__)
def test_an_ordinary_document_composes_as_pyyaml_composes_it(loader):
    text = "a: &p {x: 1, y: [2, 3.5, null, true]}\nb: *p\nc: !!str 12\n"
    ours, theirs = compose(loader, text), yaml.compose(text, Loader=yaml.SafeLoader)
    assert yaml.safe_load(yaml.serialize(ours)) == yaml.safe_load(yaml.serialize(theirs)) == {
        "a": {"x": 1, "y": [2, 3.5, None, True]}, "b": {"x": 1, "y": [2, 3.5, None, True]}, "c": "12"}


def test_a_syntax_error_keeps_the_pure_python_message_and_its_place():
    doc = parse_yaml("name: x\nroute: [1, 2\nseed: 3\n", "m.yaml")
    assert [(d.line, d.col) for d in doc.problems] == [(2, 8)]
    assert "this '[' is never closed" in doc.problems[0].message


def test_a_control_character_is_located_at_its_line():
    doc = parse_yaml("name: x\nseed: 1\x00\n", "m.yaml")
    assert [(d.line, d.col) for d in doc.problems] == [(2, 8)]

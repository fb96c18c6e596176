"""A YAML composer that enforces the document limits while it parses, before anything is expanded.

PyYAML's composer turns parser events into a node graph; this subclass counts as it goes and stops at the first
event past a limit (`mission.language.limits`): nesting depth, entries per list or mapping, uses of aliases, and the
number of values the document would hold once every alias is expanded (an alias counts as the whole subtree it
repeats, so a "billion laughs" document stops after a few hundred thousand values, not 5 GB later). An alias to a
node that contains it (a recursive document) is refused, and so is any tag beyond the plain data types, on a
scalar, a list or a mapping alike.

Two loaders share it: one over libyaml's event parser (fast; used first) and one over PyYAML's pure-Python parser,
whose syntax error messages the diagnostics are written for.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import yaml
from yaml.composer import Composer
from yaml.events import AliasEvent, CollectionStartEvent, ScalarEvent
from yaml.nodes import MappingNode, Node, SequenceNode
from yaml.parser import Parser
from yaml.reader import Reader
from yaml.resolver import Resolver
from yaml.scanner import Scanner

from mission.language.limits import MAX_ALIASES, MAX_DEPTH, MAX_ITEMS, MAX_NODES

_CORE = "tag:yaml.org,2002:"
ALLOWED_TAGS = frozenset({None, "!"} | {_CORE + t for t in ("str", "int", "float", "bool", "null", "seq", "map")})


class LimitExceeded(yaml.MarkedYAMLError):
    """A document goes past one of the limits, or uses a tag or alias that is refused. `problem_mark` locates it."""


class BoundedComposer(Composer):
    """Composer with limits; mix it in before a parser (see `FastLoader` and `ExactLoader`)."""

    if TYPE_CHECKING:  # provided by the parser it is mixed with
        def check_event(self, *choices: Any) -> bool: ...

        def peek_event(self) -> Any: ...

    def init_bounds(self) -> None:
        self._depth = 0
        self._aliases = 0
        self._nodes = 0
        self._weights: dict[int, int] = {}  # id(anchored node) -> values it holds, once composed

    def _refuse(self, problem: str, mark: Any) -> None:
        raise LimitExceeded(problem=problem, problem_mark=mark)

    def _count(self, values: int, mark: Any) -> None:
        self._nodes += values
        if self._nodes > MAX_NODES:
            self._refuse(f"the document holds more than {MAX_NODES:,} values (aliases expanded)", mark)

    def compose_node(self, parent: Node | None, index: Any) -> Node | None:
        if self.check_event(AliasEvent):
            event = self.peek_event()
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                self._refuse(f"more than {MAX_ALIASES} aliases (*name) in one document", event.start_mark)
            self._check_length(parent, index, event.start_mark)
            target = self.anchors.get(event.anchor)
            if target is not None:
                weight = self._weights.get(id(target))
                if weight is None:
                    self._refuse(f"the alias *{event.anchor} repeats a node that contains it (a recursive "
                                 "document)", event.start_mark)
                else:
                    self._count(weight, event.start_mark)
            return super().compose_node(parent, index)
        event = self.peek_event()
        mark = event.start_mark
        if isinstance(event, (ScalarEvent, CollectionStartEvent)) and event.tag not in ALLOWED_TAGS:
            tag = str(event.tag)
            tag = tag.replace(_CORE, "!!")
            shown = tag if len(tag) <= 60 else tag[:57] + "..."
            self._refuse(f"the tag {shown} is not allowed: mission, world and model files hold plain data "
                         "(strings, numbers, booleans, lists, mappings)", mark)
        self._check_length(parent, index, mark)
        self._depth += 1
        if self._depth > MAX_DEPTH:
            self._refuse(f"nesting deeper than {MAX_DEPTH} levels", mark)
        before = self._nodes
        self._count(1, mark)
        node = super().compose_node(parent, index)
        self._depth -= 1
        if event.anchor is not None:
            self._weights[id(node)] = self._nodes - before
        return node

    def _check_length(self, parent: Node | None, index: Any, mark: Any) -> None:
        if isinstance(parent, SequenceNode) and isinstance(index, int) and index >= MAX_ITEMS:
            self._refuse(f"a list with more than {MAX_ITEMS:,} entries", mark)
        if isinstance(parent, MappingNode) and index is None and len(parent.value) >= MAX_ITEMS:
            self._refuse(f"a mapping with more than {MAX_ITEMS:,} keys", mark)


class ExactLoader(BoundedComposer, Reader, Scanner, Parser, Resolver):
    """PyYAML's pure-Python parser under the limits: slower, with the syntax messages users know."""

    def __init__(self, stream: str):
        Reader.__init__(self, stream)
        Scanner.__init__(self)
        Parser.__init__(self)
        Composer.__init__(self)
        Resolver.__init__(self)
        self.init_bounds()


def _fast_loader() -> Any:
    try:
        from yaml._yaml import CParser
    except ImportError:  # PyYAML built without libyaml
        return None

    class FastLoader(BoundedComposer, CParser, Resolver):
        """libyaml's event parser under the limits."""

        def __init__(self, stream: str):
            CParser.__init__(self, stream)
            Composer.__init__(self)
            Resolver.__init__(self)
            self.init_bounds()

    return FastLoader


FastLoader = _fast_loader()


def compose_bounded(text: str) -> Node | None:
    """The node graph of the one document in `text`, composed under the limits.

    Raises LimitExceeded past a limit, and PyYAML's MarkedYAMLError (or YAMLError) on a syntax error, with the
    pure-Python parser's message when the text is small enough to parse twice.
    """
    if FastLoader is not None:
        loader: Any = FastLoader(text)
        try:
            return loader.get_single_node()  # type: ignore[no-any-return]
        except LimitExceeded:
            raise
        except yaml.YAMLError:
            if len(text) > 1_000_000:
                raise
        finally:
            loader.dispose()
    exact = ExactLoader(text)
    try:
        return exact.get_single_node()
    finally:
        exact.dispose()

"""Readable fuzzy rules: ``IF occlusion IS heavy AND NOT lane_confidence IS high THEN fear IS very_high``.

Grammar (keywords in any case; NOT binds tighter than AND, AND tighter than OR; parentheses group)::

    rule    := IF expr THEN fear IS level [WITH weight]
    expr    := conj (OR conj)*
    conj    := neg (AND neg)*
    neg     := NOT neg | '(' expr ')' | variable IS [NOT] term

Hand-written because scikit-fuzzy builds rules from Python operators, not from text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from fearguard.errors import RuleSyntaxError


@dataclass(frozen=True)
class Is:
    variable: str
    term: str


@dataclass(frozen=True)
class Not:
    operand: Node


@dataclass(frozen=True)
class And:
    operands: tuple[Node, ...]


@dataclass(frozen=True)
class Or:
    operands: tuple[Node, ...]


Node = Is | Not | And | Or


@dataclass(frozen=True)
class ParsedRule:
    """A rule's antecedent tree, its fear level name and its weight (0..1)."""

    antecedent: Node
    level: str
    weight: float


MAX_NESTING = 100  # [levels] of NOT and parentheses in one rule: parser, compiler and reference recurse per level

_TOKEN = re.compile(r"\s*(\(|\)|[A-Za-z_][A-Za-z0-9_]*|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|\S)")
_KEYWORDS = {"IF", "THEN", "IS", "AND", "OR", "NOT", "WITH"}


def _tokens(text: str) -> list[str]:
    return [m.group(1) for m in _TOKEN.finditer(text)]


class _Parser:
    def __init__(self, text: str) -> None:
        self.toks = _tokens(text)
        self.pos = 0
        self.depth = 0

    def peek(self) -> str | None:
        return self.toks[self.pos] if self.pos < len(self.toks) else None

    def take(self) -> str:
        tok = self.peek()
        if tok is None:
            raise RuleSyntaxError("the rule ends too early")
        self.pos += 1
        return tok

    def keyword(self, tok: str | None) -> str | None:
        return tok.upper() if tok is not None and tok.upper() in _KEYWORDS else None

    def expect(self, word: str) -> None:
        tok = self.take()
        if self.keyword(tok) != word:
            raise RuleSyntaxError(f"expected {word} but found {tok!r}")

    def name(self, what: str) -> str:
        tok = self.take()
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", tok) or self.keyword(tok):
            raise RuleSyntaxError(f"expected {what} but found {tok!r}")
        return tok

    def expr(self) -> Node:
        parts = [self.conj()]
        while self.keyword(self.peek()) == "OR":
            self.take()
            parts.append(self.conj())
        return parts[0] if len(parts) == 1 else Or(tuple(parts))

    def conj(self) -> Node:
        parts = [self.neg()]
        while self.keyword(self.peek()) == "AND":
            self.take()
            parts.append(self.neg())
        return parts[0] if len(parts) == 1 else And(tuple(parts))

    def neg(self) -> Node:
        tok = self.peek()
        if self.keyword(tok) == "NOT" or tok == "(":
            self.depth += 1
            if self.depth > MAX_NESTING:
                raise RuleSyntaxError(f"NOT and parentheses nested deeper than {MAX_NESTING} levels; simplify the rule")
            self.take()
            if tok == "(":
                inner = self.expr()
                if self.take() != ")":
                    raise RuleSyntaxError("a '(' is not closed")
            else:
                inner = Not(self.neg())
            self.depth -= 1
            return inner
        variable = self.name("a variable name")
        self.expect("IS")
        negate = self.keyword(self.peek()) == "NOT"
        if negate:
            self.take()
        atom = Is(variable, self.name(f"a term of {variable}"))
        return Not(atom) if negate else atom

    def rule(self) -> ParsedRule:
        self.expect("IF")
        antecedent = self.expr()
        self.expect("THEN")
        output = self.name("'fear'")
        if output != "fear":
            raise RuleSyntaxError(f"a rule concludes about 'fear', not {output!r}")
        self.expect("IS")
        level = self.name("a fear level")
        weight = 1.0
        if self.keyword(self.peek()) == "WITH":
            self.take()
            tok = self.take()
            try:
                weight = float(tok)
            except ValueError:
                raise RuleSyntaxError(f"WITH needs a number between 0 and 1, found {tok!r}") from None
            if not 0.0 <= weight <= 1.0:
                raise RuleSyntaxError(f"WITH needs a number between 0 and 1, found {tok}")
        if self.peek() is not None:
            raise RuleSyntaxError(f"unexpected {self.peek()!r} after the end of the rule")
        return ParsedRule(antecedent, level, weight)


def parse_rule(text: str) -> ParsedRule:
    """Parse one rule; raises RuleSyntaxError saying what was expected."""
    return _Parser(text).rule()


def atoms(node: Node) -> list[Is]:
    """Every ``variable IS term`` in the tree, left to right."""
    if isinstance(node, Is):
        return [node]
    if isinstance(node, Not):
        return atoms(node.operand)
    return [a for op in node.operands for a in atoms(op)]

"""Reads the text form of programs back (the exact inverse of ``printer.to_text``); never Python eval.

Grammar (whitespace-insensitive within a line; '#' starts a comment; one rule per line):
    file   := rule_line+ | ('round' INT ':' rule_line+)+
    rule   := 'argmax' '(' 'map' '(' linear ',' filter ')' ')'  |  'random' '(' filter ')'
    filter := 'filter' '(' cond ',' 'l' ')'
    cond   := conj ('or' conj)*        conj := atom ('and' atom)*
    atom   := 'true' | '(' cond ')' | linear ('>=' | '<=') number
    linear := ['-'] term (('+' | '-') term)*        term := number '*' NAME | NAME
Errors name the line and column.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from .ast import And, ArgMaxRule, Cond, Linear, Or, Program, RandomRule, Rule, Test, TrueCond


class ProgramSyntaxError(ValueError):
    """Malformed program text; ``line`` and ``col`` are 1-based."""

    def __init__(self, msg: str, line: int, col: int, source: str = "<program>"):
        super().__init__(f"{source}:{line}:{col}: {msg}")
        self.line, self.col, self.msg = line, col, msg


_TOKEN = re.compile(r"(?:(?P<num>\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
                    r"|(?P<op>>=|<=|[-+*(),:]))", re.ASCII)  # ASCII: digits of other scripts are not numbers
_SPACE = re.compile(r"\s*")
_COMPARISON = re.compile(r"[<>=!]+")
_USE_INSTEAD = {">": "use '>=' (or '<=')", "<": "use '<=' (or '>=')"}
"""what to write instead of a comparison the language lacks; any other ('==', '!=', '=') gets the general hint"""

MAX_LINE = 10_000
"""characters in one line of program text: a rule of the search is under 200; longer text is refused, not parsed"""
MAX_RULES = 64
"""rules in one round: each picks at most one other agent, so K past the largest team (40 agents) adds nothing; the
search writes K <= 5. A longer file is refused at its first rule over, before eval would run it for minutes"""
MAX_DEPTH = 64
"""nesting of a filter's and / or / parentheses: the search writes depth 2; deeper trees are refused before they
reach the recursive printer and evaluator"""


@dataclass
class _Tok:
    lex: str  # the lexical class: num, name, op, end
    text: str
    col: int  # 1-based


def _shown(text: str) -> str:
    """A token as an error message quotes it: at most 40 characters."""
    return repr(text if len(text) <= 40 else text[:37] + "...")


def _unexpected(line: str, pos: int) -> str:
    """The message for a character no token starts with; a comparison the language lacks says which ones it has."""
    op = _COMPARISON.match(line, pos)
    if op is None:
        return f"unexpected character {line[pos]!r}"
    hint = _USE_INSTEAD.get(op.group(), "a test compares with '>=' or '<='")
    return f"{_shown(op.group())} is not an operator of the program language; {hint}"


def _tokenize(line: str, lineno: int, source: str) -> list[_Tok]:
    """Tokens of one line, in one left-to-right pass (linear in the line's length)."""
    if len(line) > MAX_LINE:
        raise ProgramSyntaxError(f"line is {len(line):,} characters long; a rule fits in {MAX_LINE:,}", lineno, 1,
                                 source)
    toks, pos = [], _SPACE.match(line, 0).end()
    while pos < len(line):
        m = _TOKEN.match(line, pos)
        if not m:
            raise ProgramSyntaxError(_unexpected(line, pos), lineno, pos + 1, source)
        lex = m.lastgroup or "op"
        toks.append(_Tok(lex, m.group(lex), m.start(lex) + 1))
        pos = _SPACE.match(line, m.end()).end()
    toks.append(_Tok("end", "", len(line.rstrip()) + 1))
    return toks


class _LineParser:
    def __init__(self, toks: list[_Tok], lineno: int, source: str):
        self.toks, self.i, self.lineno, self.source = toks, 0, lineno, source

    def peek(self) -> _Tok:
        return self.toks[self.i]

    def fail(self, msg: str, tok: _Tok | None = None) -> ProgramSyntaxError:
        tok = tok or self.peek()
        found = "end of line" if tok.lex == "end" else _shown(tok.text)
        return ProgramSyntaxError(f"{msg}, found {found}", self.lineno, tok.col, self.source)

    def expect(self, text: str) -> _Tok:
        tok = self.peek()
        if tok.text != text or tok.lex == "end":
            raise self.fail(f"expected {text!r}")
        self.i += 1
        return tok

    def accept(self, text: str) -> bool:
        if self.peek().text == text and self.peek().lex != "end":
            self.i += 1
            return True
        return False

    def number(self) -> float:
        neg = self.accept("-")
        tok = self.peek()
        if tok.lex != "num":
            raise self.fail("expected a number")
        self.i += 1
        v = self.finite(tok)
        return -v if neg else v

    def finite(self, tok: _Tok) -> float:
        """The value of a number token; one that overflows a float (1e400) is an error, not inf."""
        v = float(tok.text)
        if not math.isfinite(v):
            raise ProgramSyntaxError(f"number {_shown(tok.text)} is out of range", self.lineno, tok.col, self.source)
        return v

    def term(self, sign: float) -> tuple[str, float]:
        tok = self.peek()
        if tok.lex == "num":
            w = self.finite(tok)
            self.i += 1
            self.expect("*")
            tok = self.peek()
        else:
            w = 1.0
        if tok.lex != "name" or tok.text in ("and", "or", "true", "l"):
            raise self.fail("expected a feature name")
        self.i += 1
        return tok.text, sign * w

    def linear(self) -> Linear:
        start = self.peek()
        terms = [self.term(-1.0 if self.accept("-") else 1.0)]
        while self.peek().text in ("+", "-") and self.peek().lex == "op":
            sign = -1.0 if self.peek().text == "-" else 1.0
            self.i += 1
            terms.append(self.term(sign))
        names = [n for n, _ in terms]
        if len(set(names)) != len(names):
            raise self.fail("a feature appears twice in one linear form", start)
        return Linear(tuple(terms))

    def atom(self, depth: int) -> Cond:
        if self.peek().lex == "name" and self.peek().text == "true":
            self.i += 1
            return TrueCond()
        if self.peek().text == "(" and self.peek().lex == "op":
            self.nest(depth)
            self.i += 1
            c = self.cond(depth + 1)
            self.expect(")")
            return c
        lhs = self.linear()
        if self.accept("<="):  # F <= c  is  -F >= -c
            return Test(Linear(tuple((n, -w) for n, w in lhs.terms)), -self.number())
        self.expect(">=")
        return Test(lhs, self.number())

    def nest(self, depth: int) -> None:
        """Each 'and', 'or' and parenthesis adds a level to the filter's tree; refuse trees deeper than MAX_DEPTH."""
        if depth >= MAX_DEPTH:
            raise self.fail(f"filter nested deeper than {MAX_DEPTH} levels")

    def conj(self, depth: int) -> Cond:
        c = self.atom(depth)
        while self.peek().lex == "name" and self.peek().text == "and":
            depth += 1
            self.nest(depth)
            self.i += 1
            c = And(c, self.atom(depth))
        return c

    def cond(self, depth: int = 0) -> Cond:
        c = self.conj(depth)
        while self.peek().lex == "name" and self.peek().text == "or":
            depth += 1
            self.nest(depth)
            self.i += 1
            c = Or(c, self.conj(depth))
        return c

    def filter(self) -> Cond:
        self.expect("filter")
        self.expect("(")
        c = self.cond()
        self.expect(",")
        self.expect("l")
        self.expect(")")
        return c

    def rule(self) -> Rule:
        tok = self.peek()
        if tok.text == "argmax":
            self.i += 1
            self.expect("(")
            self.expect("map")
            self.expect("(")
            score = self.linear()
            self.expect(",")
            cond = self.filter()
            self.expect(")")
            self.expect(")")
            r: Rule = ArgMaxRule(score, cond)
        elif tok.text == "random":
            self.i += 1
            self.expect("(")
            cond = self.filter()
            self.expect(")")
            r = RandomRule(cond)
        else:
            raise self.fail("expected a rule: argmax(map(...)) or random(filter(...))")
        if self.peek().lex != "end":
            raise self.fail("expected end of line after the rule")
        return r


def parse(text: str, source: str = "<program>") -> Program:
    """Parse program text; raises ProgramSyntaxError with line and column."""
    rounds: list[list[Rule]] = []
    headed = None
    text = text.removeprefix("\ufeff")  # a byte order mark, as some editors save UTF-8: not part of the program
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0]
        if not line.strip():
            continue
        toks = _tokenize(line, lineno, source)
        if toks[0].text == "round":
            if headed is False:
                raise ProgramSyntaxError("a 'round' header after rules without one", lineno, toks[0].col, source)
            headed = True
            p = _LineParser(toks, lineno, source)
            p.i = 1
            num = p.peek()
            if num.lex != "num" or not num.text.isdigit() or int(num.text) != len(rounds) + 1:
                raise p.fail(f"expected round number {len(rounds) + 1}")
            p.i += 1
            p.expect(":")
            if p.peek().lex != "end":
                raise p.fail("expected end of line after the round header")
            rounds.append([])
            continue
        if headed is None:
            headed = False
            rounds.append([])
        if len(rounds[-1]) == MAX_RULES:
            raise ProgramSyntaxError(f"round {len(rounds)} has more than {MAX_RULES} rules (at most {MAX_RULES}: "
                                     "each rule picks one other agent)", lineno, toks[0].col, source)
        rounds[-1].append(_LineParser(toks, lineno, source).rule())
    if not rounds or any(not r for r in rounds):
        raise ProgramSyntaxError("a program needs at least one rule in every round", max(1, len(text.splitlines())), 1,
                                 source)
    return Program(tuple(tuple(r) for r in rounds))

"""The communication-program language: immutable AST, exact printer and parser, batched evaluator."""

from .ast import And, ArgMaxRule, Cond, Linear, Or, Program, RandomRule, Rule, Test, TrueCond
from .parser import ProgramSyntaxError, parse
from .printer import describe, rule_text, to_text

__all__ = ["And", "ArgMaxRule", "Cond", "Linear", "Or", "Program", "ProgramSyntaxError", "RandomRule", "Rule",
           "Test", "TrueCond", "describe", "parse", "rule_text", "to_text"]

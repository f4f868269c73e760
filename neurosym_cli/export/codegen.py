"""The program as code a robot can run without neurosym: a standard-library Python module and a single-header
C99 function, both written from the same structure so they read alike.

Per round ``r`` (1-based) there is one function per rule, ``round<r>_rule<k>`` (the rule's text and reading as a
comment above it), and one per round, ``round<r>`` (C: ``ns_round<r>``), returning one agent index per rule. Per
feature there is one function named after it (``feature_<name>``, C ``ns_feature_<name>``) with its meaning and
unit. The semantics are spec.SEMANTICS_TEXT. Features are computed in double precision (neurosym computes in
float32): picks can differ only where a feature lies within float32 rounding of a threshold or two candidates'
scores tie within it (docs/deploy.md, 'Limits').
"""

from __future__ import annotations

import keyword
from dataclasses import dataclass

from ..dsl.ast import And, Cond, Linear, Or, Program, RandomRule, Rule, Test, TrueCond, rule_features
from ..dsl.printer import describe, fmt_float, rule_text, to_text
from ..dsl.vocabulary import Feature, FeatureSet
from . import SEMANTICS
from .spec import check_finite, used_features

_C_KEYWORDS = {"auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum",
               "extern", "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return",
               "short", "signed", "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void",
               "volatile", "while", "_Bool", "_Complex", "_Imaginary"}
_TAKEN = {"me", "o", "others", "i", "j", "n", "uniform", "state", "pick", "best", "score", "u", "math", "picks",
          "hypot", "atan2", "NULL", "size_t"}


def local(name: str) -> str:
    """A feature's local variable name: its own, unless that is a keyword or a name the generated code uses."""
    return f"{name}_v" if name in _TAKEN or name in _C_KEYWORDS or keyword.iskeyword(name) else name


@dataclass(frozen=True)
class _Lang:
    """What differs between the two languages: operators, literals, calls."""

    and_: str
    or_: str
    true: str
    hypot: str
    atan2: str
    feature: str  # prefix of a feature function's name
    null: str

    def call(self, f: str, own: bool) -> str:
        return f"{self.feature}{f}(me, {self.null if own else 'o'})"


PY = _Lang("and", "or", "True", "math.hypot", "math.atan2", "feature_", "None")
C = _Lang("&&", "||", "1", "hypot", "atan2", "ns_feature_", "0")


def _own(f: Feature, vocab: FeatureSet) -> bool:
    """Computed from the asking agent's input alone (hoisted out of the loop over candidates)."""
    s = f.source
    assert s is not None
    return all(_own(vocab.get(p), vocab) for p in s.product) if s.product else s.field == "agent"


def _feature_expr(f: Feature, lang: _Lang) -> str:
    """The feature's value from ``me`` (s_i) and ``o`` (o_ij) as an expression."""
    s = f.source
    assert s is not None
    if s.product:
        return " * ".join(f"{lang.feature}{p}(me, o)" for p in s.product)
    arr = "me" if s.field == "agent" else "o"
    neg = "-" if s.sign < 0 else ""
    x, y = f"{neg}{arr}[{s.start}]", f"{neg}{arr}[{s.start + 1}]"
    return {"x": x, "y": y, "d": f"{lang.hypot}({x}, {y})", "theta": f"{lang.atan2}({y}, {x})"}[s.part]


def _linear(f: Linear) -> str:
    """sum_k w_k phi_k in the written order (neurosym sums in that order), over the features' local names."""
    if not f.terms:
        return "0.0"
    return " + ".join(local(n) if w == 1.0 else f"{fmt_float(w)} * {local(n)}" for n, w in f.terms)


def _cond(c: Cond, lang: _Lang) -> str:
    if isinstance(c, TrueCond):
        return lang.true
    if isinstance(c, Test):
        if len(c.lhs.terms) == 1 and c.lhs.terms[0][1] == -1.0:  # -f >= c is exactly f <= -c (negation is exact)
            return f"{local(c.lhs.terms[0][0])} <= {fmt_float(-c.threshold)}"
        return f"{_linear(c.lhs)} >= {fmt_float(c.threshold)}"
    op = lang.and_ if isinstance(c, And) else lang.or_
    return f"({_cond(c.left, lang)} {op} {_cond(c.right, lang)})"


def _rule_features(r: Rule, vocab: FeatureSet) -> tuple[list[Feature], list[Feature]]:
    """(own features, hoisted; the candidate's, per j) that rule r reads, in the task's order."""
    names = rule_features(r)
    fs = [f for f in vocab.features if f.name in names]
    return [f for f in fs if _own(f, vocab)], [f for f in fs if not _own(f, vocab)]


def _unit(f: Feature) -> str:
    """' (unit)' after a feature's words, unless the words already say it."""
    return f" ({f.unit})" if f.unit and f"({f.unit})" not in f.words else ""


def _header_lines(program: Program, vocab: FeatureSet, task: str, version: str) -> list[str]:
    return [f"Communication program exported by neurosym: task {task}, features {version}, semantics {SEMANTICS}.",
            "", "The program (paper notation):", *("  " + ln for ln in to_text(program).splitlines())]


# ------------------------------------------------------------------------------------------------ Python
def python_module(program: Program, vocab: FeatureSet, task: str, version: str, agent_dim: int,
                  pair_dim: int) -> str:
    """program.py: the program as a dependency-free Python module (the standard library's math only)."""
    check_finite(program)
    feats = used_features(program, vocab, task)
    head = _header_lines(program, vocab, task, version)
    out = ['"""' + head[0], *head[1:], "",
           "One function per round: round<r>(me, others, i, uniform=None) -> one agent index per rule, in rule",
           "order, -1 where the rule's filter passes nobody (an agent picked by two rules is heard once: heard()).",
           f"  me       s_i, agent i's own input: {agent_dim} floats",
           f"  others   o_ij for j = 0..n-1: n rows of {pair_dim} floats, agent i's view of agent j (row i is ignored)",
           "  i        agent i's index among the n",
           "  uniform  a zero-argument callable returning a float in [0, 1), e.g. random.random. Each random rule",
           "           calls it exactly n times, once per j = 0..n-1 in index order (i itself and rejected agents",
           "           included, also when nobody passes), the random rules of a round in rule order; argmax rules",
           "           never call it. Feeding it row i of the (n, n) uniforms neurosym drew for that rule reproduces",
           "           neurosym's picks. Not needed by a round without random rules.",
           '"""', "", "import math", "",
           f'SEMANTICS = "{SEMANTICS}"',
           f"AGENT_DIM = {agent_dim}  # floats in me",
           f"PAIR_DIM = {pair_dim}  # floats in each row of others",
           f"RULES = {tuple(len(rs) for rs in program.rounds)!r}  # rules per round",
           f"RANDOM_RULES = {tuple(sum(isinstance(r, RandomRule) for r in rs) for rs in program.rounds)!r}"
           "  # per round: uniform draws = RANDOM_RULES[r] * n", "", "",
           "# ------------------------------------------------------------------ features", ""]
    for f in feats:
        unit = _unit(f)
        out += [f"def feature_{f.name}(me, o):", f'    """{f.name}: {f.words}{unit}"""',
                f"    return {_feature_expr(f, PY)}", "", ""]
    names = []
    for r, rules in enumerate(program.rounds, start=1):
        out += [f"# ------------------------------------------------------------------ round {r}", ""]
        for k, rule in enumerate(rules, start=1):
            names.append((r, k))
            out += _py_rule(rule, r, k, vocab)
        calls = ", ".join(f"round{r}_rule{k}(me, others, i, uniform)" for k in range(1, len(rules) + 1))
        need = any(isinstance(x, RandomRule) for x in rules)
        out += [f"def round{r}(me, others, i, uniform=None):",
                f'    """Round {r}: agent i\'s pick under each of the round\'s {len(rules)} rule(s), -1 for nobody."""']
        if need:
            out += ["    if uniform is None:",
                    f'        raise ValueError("round {r} has a random rule: pass a uniform source")']
        out += [f"    return [{calls}]", "", ""]
    out += [f"ROUNDS = ({', '.join(f'round{r}' for r in range(1, program.n_rounds + 1))},)", "", "",
            "def heard(picks):", '    """The agents heard: the valid picks, each once, in rule order."""',
            "    out = []", "    for p in picks:", "        if p >= 0 and p not in out:", "            out.append(p)",
            "    return out", ""]
    return "\n".join(out)


def _py_rule(rule: Rule, r: int, k: int, vocab: FeatureSet) -> list[str]:
    own, other = _rule_features(rule, vocab)
    rnd = isinstance(rule, RandomRule)
    out = [f"# {rule_text(rule)}", f"def round{r}_rule{k}(me, others, i, uniform):",
           f'    """{describe(rule, vocab)}"""']
    out += [f"    {local(f.name)} = {PY.call(f.name, True)}" for f in own]
    out += ["    pick, best = -1, 0.0", "    for j, o in enumerate(others):"]
    if rnd:
        out += ["        u = uniform()  # one draw per index j, before any test, so the stream stays in step"]
    out += ["        if j == i:", "            continue"]
    out += [f"        {local(f.name)} = {PY.call(f.name, False)}" for f in other]
    score = "u" if rnd else _linear(rule.score)  # type: ignore[union-attr]
    test = _cond(rule.cond, PY)
    test = test[1:-1] if isinstance(rule.cond, (And, Or)) else test  # the if needs no outer parentheses
    out += [f"        if {test}:",
            f"            score = {score}",
            "            if pick < 0 or score > best:  # strictly better: ties keep the lowest index",
            "                pick, best = j, score", "    return pick", "", ""]
    return out


# ------------------------------------------------------------------------------------------------ C99
def c_header(program: Program, vocab: FeatureSet, task: str, version: str, agent_dim: int, pair_dim: int) -> str:
    """program.h: the program as one C99 header (static inline functions, no allocation, no globals)."""
    check_finite(program)
    feats = used_features(program, vocab, task)
    head = _header_lines(program, vocab, task, version)
    out = ["/* " + head[0], *[(" * " + ln).rstrip() for ln in head[1:]], " *",
           " * int ns_round<r>(const double *me, const double *others, int n, int i,",
           " *                 ns_uniform_fn uniform, void *state, int *picks)",
           f" *   me       s_i, agent i's own input: NS_AGENT_DIM = {agent_dim} doubles",
           f" *   others   o_ij for j = 0..n-1, row-major n x NS_PAIR_DIM = {pair_dim} doubles (row i is ignored)",
           " *   n, i     team size (1..NS_MAX_AGENTS) and agent i's index",
           " *   uniform  returns a double in [0, 1) from state; each random rule calls it exactly n times, once per",
           " *            j = 0..n-1 in index order (i and rejected agents included, also when nobody passes), the",
           " *            random rules of a round in rule order; argmax rules never call it (may be 0 then)",
           " *   picks    out: one agent index per rule, -1 where the rule's filter passes nobody",
           " * returns the number of rules written (NS_ROUND<r>_RULES), or -1 for n or i out of range or a random",
           " * rule without a uniform source. No allocation, no globals: safe to call from any thread.",
           " */", "#ifndef NEUROSYM_PROGRAM_H", "#define NEUROSYM_PROGRAM_H", "", "#include <math.h>",
           "#include <stddef.h>", "", "#ifndef NS_MAX_AGENTS",
           "#define NS_MAX_AGENTS 4096 /* the largest team the functions accept: bounds every loop */", "#endif",
           f'#define NS_SEMANTICS "{SEMANTICS}"', f"#define NS_AGENT_DIM {agent_dim}", f"#define NS_PAIR_DIM {pair_dim}",
           f"#define NS_ROUNDS {program.n_rounds}",
           f"#define NS_MAX_RULES {max(len(rs) for rs in program.rounds)}"]
    for r, rules in enumerate(program.rounds, start=1):
        out.append(f"#define NS_ROUND{r}_RULES {len(rules)}")
        out.append(f"#define NS_ROUND{r}_RANDOM_RULES {sum(isinstance(x, RandomRule) for x in rules)}")
    out += ["", "typedef double (*ns_uniform_fn)(void *state);", "", "/* ---- features */", ""]
    for f in feats:
        unit = _unit(f)
        out += [f"/* {f.name}: {f.words}{unit} */",
                f"static inline double ns_feature_{f.name}(const double *me, const double *o)",
                "{", "    (void)me;", "    (void)o;", f"    return {_feature_expr(f, C)};", "}", ""]
    for r, rules in enumerate(program.rounds, start=1):
        out += [f"/* ---- round {r} */", ""]
        for k, rule in enumerate(rules, start=1):
            out += _c_rule(rule, r, k, vocab)
        need = any(isinstance(x, RandomRule) for x in rules)
        out += [f"/* Round {r}: agent i's pick under each of the round's {len(rules)} rule(s), -1 for nobody. */",
                f"static inline int ns_round{r}(const double *me, const double *others, int n, int i,",
                "                            ns_uniform_fn uniform, void *state, int *picks)", "{",
                "    if (n < 1 || n > NS_MAX_AGENTS || i < 0 || i >= n) return -1;"]
        if need:
            out.append("    if (uniform == 0) return -1;")
        out += [f"    picks[{k - 1}] = ns_round{r}_rule{k}(me, others, n, i, uniform, state);"
                for k in range(1, len(rules) + 1)]
        out += [f"    return {len(rules)};", "}", ""]
    out += ["/* Round r (1-based) by number; -1 for a round the program does not have. */",
            "static inline int ns_round(int r, const double *me, const double *others, int n, int i,",
            "                           ns_uniform_fn uniform, void *state, int *picks)", "{"]
    out += [f"    if (r == {r}) return ns_round{r}(me, others, n, i, uniform, state, picks);"
            for r in range(1, program.n_rounds + 1)]
    out += ["    return -1;", "}", "", "#endif /* NEUROSYM_PROGRAM_H */", ""]
    return "\n".join(out)


def _c_rule(rule: Rule, r: int, k: int, vocab: FeatureSet) -> list[str]:
    own, other = _rule_features(rule, vocab)
    rnd = isinstance(rule, RandomRule)
    out = [f"/* {rule_text(rule)} */", f"/* {describe(rule, vocab)} */",
           f"static inline int ns_round{r}_rule{k}(const double *me, const double *others, int n, int i,",
           "                                  ns_uniform_fn uniform, void *state)", "{"]
    out += [f"    const double {local(f.name)} = {C.call(f.name, True)};" for f in own]
    out += ["    int pick = -1, j;", "    double best = 0.0;", "    (void)me;"]
    if not rnd:
        out += ["    (void)uniform;", "    (void)state;"]
    out += ["    for (j = 0; j < n; j++) {", "        const double *o = others + (size_t)j * NS_PAIR_DIM;"]
    if rnd:
        out += ["        const double u = uniform(state); /* one draw per index j, before any test */"]
    out += ["        (void)o;", "        if (j == i) continue;", "        {"]
    out += [f"            const double {local(f.name)} = {C.call(f.name, False)};" for f in other]
    score = "u" if rnd else _linear(rule.score)  # type: ignore[union-attr]
    out += [f"            if ({_cond(rule.cond, C)}) {{", f"                const double score = {score};",
            "                if (pick < 0 || score > best) { pick = j; best = score; } /* ties: lowest index */",
            "            }", "        }", "    }", "    return pick;", "}", ""]
    return out

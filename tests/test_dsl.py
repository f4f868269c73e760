"""The program language: evaluator semantics on hand-built features, exact text round-trip, parser errors."""

import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from neurosym_cli.dsl import And, ArgMaxRule, Linear, Or, Program, ProgramSyntaxError, RandomRule, TrueCond
from neurosym_cli.dsl import Test as T
from neurosym_cli.dsl import describe, parse, to_text
from neurosym_cli.dsl.vocabulary import FeatureSet
from fixtures import feature_map

# every feature the paper's tasks declare (formation v2, unlabeled-goals v1): the words the readings are built of
VOCAB = FeatureSet(tuple({f.name: f for fm in (feature_map("formation", "v2"), feature_map("unlabeled", "v1", 10))
                          for f in fm.vocab.features}.values()))
from neurosym_cli.dsl.interpret import program_mask, rule_picks


class Feats:
    """A FeatureView over hand-built tensors: pair features (B, N, N), agent features (B, N, 1)."""

    def __init__(self, **named):
        self.named = named
        any_pair = next(v for v in named.values() if v.shape[-1] == v.shape[-2])
        self.batch, self.n_agents = any_pair.shape[0], any_pair.shape[1]
        self.rows, self.first = self.n_agents, 0  # every agent asks (a chunk of receivers: rows < N, first > 0)
        self.device = any_pair.device

    def __getitem__(self, name):
        return self.named[name]


class Uniform:
    def __init__(self, seed):
        self.g = torch.Generator().manual_seed(seed)

    def rand(self, b, *shape):
        return torch.rand(b, *shape, generator=self.g)


def _d():
    # 1 episode, 4 agents on a line at x = 0, 1, 3, 7 (no ties)
    x = torch.tensor([0.0, 1.0, 3.0, 7.0])
    dx = (x[None, :] - x[:, None])[None]  # (1, 4, 4): x_j - x_i
    return Feats(d=dx.abs(), dx=dx, gd=torch.tensor([[[5.0], [1.0], [2.0], [0.5]]]))


def test_argmax_picks_the_best_filtered_agent():
    f = _d()
    nearest = ArgMaxRule(Linear((("d", -1.0),)), TrueCond())
    assert rule_picks(nearest, f, None).tolist() == [[1, 0, 1, 2]]
    right_nearest = ArgMaxRule(Linear((("d", -1.0),)), T(Linear((("dx", 1.0),)), 0.5))  # only agents to the right
    assert rule_picks(right_nearest, f, None).tolist() == [[1, 2, 3, -1]]  # agent 3 has nobody to its right
    farthest = ArgMaxRule(Linear((("d", 1.0),)), TrueCond())
    assert rule_picks(farthest, f, None).tolist() == [[3, 3, 3, 0]]


def test_self_is_never_picked_and_agent_features_broadcast():
    f = _d()
    r = ArgMaxRule(Linear((("d", -1.0),)), T(Linear((("gd", 1.0),)), 1.5))  # only agents with gd >= 1.5 ask
    assert rule_picks(r, f, None).tolist() == [[1, -1, 1, -1]]


def test_and_or():
    f = _d()
    a = T(Linear((("dx", 1.0),)), 0.5)  # to the right
    b = T(Linear((("d", 1.0),)), 2.5)  # at least 2.5 away
    m_and = program_mask(Program(((ArgMaxRule(Linear((("d", -1.0),)), And(a, b)),),)), 0, f, None)
    assert m_and[0].nonzero().tolist() == [[0, 2], [1, 3], [2, 3]]
    m_or = program_mask(Program(((ArgMaxRule(Linear((("d", -1.0),)), Or(a, b)),),)), 0, f, None)
    assert m_or[0].nonzero().tolist() == [[0, 1], [1, 2], [2, 0], [3, 2]]


def test_random_picks_only_filtered_agents_uniformly():
    n = 6
    d = torch.arange(n, dtype=torch.float32).expand(1, n, n).clone()  # d_ij = j
    f = Feats(d=d)
    rule = RandomRule(T(Linear((("d", 1.0),)), 2.0))  # j in {2, 3, 4, 5}, minus self
    counts = torch.zeros(n)
    src = Uniform(0)
    for _ in range(2000):
        p = rule_picks(rule, f, src)[0, 0]  # agent 0
        counts[p] += 1
    assert counts[:2].sum() == 0
    freq = counts[2:] / counts.sum()
    assert (freq - 0.25).abs().max() < 0.04
    # agent 3 cannot pick itself
    assert all(int(rule_picks(rule, f, src)[0, 3]) in (2, 4, 5) for _ in range(50))


def test_empty_filter_gives_no_edge_and_mask_is_union():
    f = _d()
    never = ArgMaxRule(Linear((("d", 1.0),)), T(Linear((("d", 1.0),)), 100.0))
    near = ArgMaxRule(Linear((("d", -1.0),)), TrueCond())
    m = program_mask(Program(((never, near, near),)), 0, f, None)
    assert m.sum(-1).tolist() == [[1, 1, 1, 1]]  # duplicates collapse, the empty rule adds nothing


# ------------------------------------------------------------------------------------- round trip
NAMES = st.sampled_from(["d", "theta", "dx", "dy", "gd", "gtheta", "gx_dy", "g10x"])
FLOATS = st.floats(allow_nan=False, allow_infinity=False, width=64, min_value=-1e6, max_value=1e6)


@st.composite
def linears(draw):
    names = draw(st.lists(NAMES, min_size=1, max_size=3, unique=True))
    return Linear(tuple((n, draw(FLOATS)) for n in names))


def conds(depth=2):
    leaf = st.one_of(st.just(TrueCond()), st.builds(T, linears(), FLOATS))
    if depth == 0:
        return leaf
    sub = conds(depth - 1)
    return st.one_of(leaf, st.builds(And, sub, sub), st.builds(Or, sub, sub))


RULES = st.one_of(st.builds(ArgMaxRule, linears(), conds()), st.builds(RandomRule, conds()))
PROGRAMS = st.lists(st.lists(RULES, min_size=1, max_size=5).map(tuple), min_size=1, max_size=3).map(
    lambda rs: Program(tuple(rs)))


@settings(max_examples=300, deadline=None)
@given(PROGRAMS)
def test_parse_print_round_trip(p):
    text = to_text(p)
    assert parse(text) == p
    assert to_text(parse(text)) == text
    for rules in p.rounds:
        for r in rules:
            reading = describe(r, VOCAB)
            # a reading says whom the rule asks, after its guard when it has one
            who = "ask a random agent" if isinstance(r, RandomRule) else "ask the"
            assert reading.startswith(who) or (reading.startswith("while ") and who in reading), reading
    assert to_text(p) == text  # reading a program never changes its text


def test_paper_examples_read_as_written():
    text = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.41, l))\n"
    p = parse(text)
    assert to_text(p) == text
    assert p.rounds[0][0] == ArgMaxRule(Linear((("d", -1.0),)), T(Linear((("theta", 1.0),)), -1.85))
    assert describe(p.rounds[0][0], VOCAB) == "ask the nearest agent whose bearing (rad) is at least -1.85"
    assert describe(p.rounds[0][1], VOCAB) == "ask a random agent at least 3.41 away"
    assert parse("random(filter(d <= 2.5, l))").rounds[0][0].cond == T(Linear((("d", -1.0),)), -2.5)


def test_comments_and_rounds():
    text = "# made by synth\nround 1:\n  random(filter(true, l))  # anyone\nround 2:\n  argmax(map(d, filter(true, l)))\n"
    p = parse(text)
    assert p.n_rounds == 2 and p.rounds[1][0] == ArgMaxRule(Linear((("d", 1.0),)), TrueCond())


@pytest.mark.parametrize("text,line,col", [
    ("argmax(map(-1.0*d, filter(theta >= , l)))", 1, 36),
    ("random(filter(d >= 3.41, l)", 1, 28),
    ("random(filter(d >= 3.41, l))\nrandom(filter(d >== 3.41, l))", 2, 19),
    ("random(filter(d >= 1, l))\nrandom(filter(d >= 1 and, l))", 2, 25),
    ("argmax(filter(d >= 1, l))", 1, 8),
    ("random(filter(d ! 1, l))", 1, 17),
    ("round 2:\n  random(filter(true, l))", 1, 7),
    ("", 1, 1),
])
def test_parser_reports_line_and_column(text, line, col):
    with pytest.raises(ProgramSyntaxError) as e:
        parse(text)
    assert (e.value.line, e.value.col) == (line, col), str(e.value)
    assert f":{line}:{col}:" in str(e.value)


@pytest.mark.parametrize("text,col,hint", [
    ("random(filter(d > 3.41, l))", 17, "'>' is not an operator of the program language; use '>=' (or '<=')"),
    ("random(filter(d < 3.41, l))", 17, "'<' is not an operator of the program language; use '<=' (or '>=')"),
    ("random(filter(d == 3.41, l))", 17, "'==' is not an operator of the program language; a test compares with "
                                         "'>=' or '<='"),
])
def test_a_missing_comparison_names_the_ones_the_language_has(text, col, hint):
    with pytest.raises(ProgramSyntaxError) as e:
        parse(text, source="my.txt")
    assert str(e.value) == f"my.txt:1:{col}: {hint}"
    assert parse(text.replace(">", ">=").replace("<", "<=").replace("==", ">=")).rounds  # the hint parses


FAMILIES = [("formation", 0), ("unlabeled", 10)]


@pytest.mark.parametrize("kind,goals", FAMILIES)
@pytest.mark.parametrize("version", ["v1", "v2"])
def test_every_feature_reads_with_its_subject(kind, goals, version):
    """A test on the asking agent's own state is a guard ('while my ...'); one on the other agent selects
    ('ask a random agent whose ... / within / for which ... its ...'). A score on the agent's own state ties every
    candidate, and the reading says so."""
    vocab = feature_map(kind, version, goals).vocab
    for name in vocab.names:
        test = describe(parse(f"random(filter({name} >= 1.5, l))").rounds[0][0], vocab)
        score = describe(parse(f"argmax(map({name}, filter(true, l)))").rounds[0][0], vocab)
        if vocab.agent_level(name):
            assert test == f"while {vocab.words(name)} is at least 1.5, ask a random agent; otherwise ask nobody"
            assert vocab.words(name).startswith("my ")
            assert score.startswith("ask the lowest-index agent (the score, ") and "agent order" in score
        else:
            assert test.startswith("ask a random agent ") and "while" not in test, test
            assert any(w in test for w in ("whose ", " its ", " away")) and "lowest-index" not in score, (test, score)


@pytest.mark.parametrize("text,reading", [
    ("random(filter(gd >= 7.46, l))",
     "while my distance to my goal is at least 7.46, ask a random agent; otherwise ask nobody"),
    ("random(filter(gy >= 0.04, l))",
     "while my y-offset to my goal is at least 0.04, ask a random agent; otherwise ask nobody"),
    ("random(filter(d <= 2.06 and gd >= 7.46, l))",
     "while my distance to my goal is at least 7.46, ask a random agent within 2.06; otherwise ask nobody"),
    ("random(filter(gy >= 0.58 or d >= 7.78, l))",
     "ask a random agent (any agent if my y-offset to my goal is at least 0.58, otherwise only those at least "
     "7.78 away)"),
    ("argmax(map(gd, filter(dy >= 2.37 and d <= 1.14, l)))",
     "ask the lowest-index agent whose y-offset is at least 2.37 and within 1.14 (the score, my distance to my "
     "goal, is the same for every candidate, so argmax falls to agent order)"),
    ("argmax(map(-1.0*theta, filter(theta >= 1.22 and gd <= 12.85, l)))",
     "while my distance to my goal is at most 12.85, ask the agent with the smallest bearing (rad) whose bearing "
     "(rad) is at least 1.22; otherwise ask nobody"),
    ("argmax(map(-1.0*d, filter(d >= 1.29 or theta <= -0.34, l)))",
     "ask the nearest agent for which its distance is at least 1.29 or its bearing (rad) is at most -0.34"),
    ("random(filter(g3d >= 2.0, l))",
     "while my distance to my goal 3 (by initial distance) is at least 2.0, ask a random agent; otherwise ask nobody"),
])
def test_hand_written_readings(text, reading):
    p = parse(text)
    assert describe(p.rounds[0][0], VOCAB) == reading
    assert to_text(p) == text + "\n"

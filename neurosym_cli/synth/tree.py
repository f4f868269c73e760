"""The decision-tree baseline of paper appendix B (dt): a tree over the program features phi(s_i, o_ij) that
imitates a *global* hard attention with max in- and out-degree <= k, derived from the oracle's soft attention.

The tree is fitted with scikit-learn (optional extra ``neurosym[dt]``) and stored as plain JSON arrays (never
pickled); ``TreeModel.predict`` evaluates it on torch feature tensors, batched over all pairs.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from functools import cached_property

import torch
from torch import Tensor

from ..config import UserError
from ..tasks.features import FeatureView
from ..utils.ops import softmax_last
from ..policy.transformer import CommTransformer
from .dataset import DataBucket


@torch.no_grad()
def soft_attention(policy: CommTransformer, b: DataBucket, round_idx: int, chunk: int = 2048) -> Tensor:
    """(S, N, N) the oracle's attention weights of one round, self excluded (full communication)."""
    out = []
    for c in range(0, b.states, chunk):
        agent, rel = b.agent[c:c + chunk], b.rel[c:c + chunk]
        h = torch.relu(policy.embed(agent))
        logits = policy.rounds[round_idx].logits(h, rel)
        eye = torch.eye(b.n_agents, dtype=torch.bool)
        out.append(softmax_last(logits.masked_fill(eye, float("-inf"))))
    return torch.cat(out)


def greedy_hard_attention(attn: Tensor, k: int) -> Tensor:
    """(S, N, N) weights -> (S, N, N) bool: pairs taken in decreasing weight while in_i < k and out_j < k.

    The reference's global hard attention, vectorised over states (one pass over the N^2 ranks)."""
    s, n, _ = attn.shape
    order = attn.flatten(1).argsort(-1, descending=True)  # (S, N N)
    deg_in = torch.zeros(s, n, dtype=torch.long)
    deg_out = torch.zeros(s, n, dtype=torch.long)
    take = torch.zeros(s, n * n, dtype=torch.bool)
    rows = torch.arange(s)
    for r in range(n * n):
        idx = order[:, r]
        i, j = idx // n, idx % n
        ok = (i != j) & (deg_in[rows, i] < k) & (deg_out[rows, j] < k) & (attn.flatten(1)[rows, idx] > 0)
        take[rows[ok], idx[ok]] = True
        deg_in[rows[ok], i[ok]] += 1
        deg_out[rows[ok], j[ok]] += 1
    return take.view(s, n, n)


@dataclass(frozen=True)
class TreeModel:
    """A fitted binary tree: node arrays as scikit-learn lays them out (leaves have left = right = -1)."""

    features: list[str]  # names of the columns the tree was fitted on
    left: list[int]
    right: list[int]
    feature: list[int]
    threshold: list[float]
    label: list[bool]  # the predicted class at each node (used at leaves)

    def to_dict(self) -> dict:
        return asdict(self)

    @staticmethod
    def from_dict(d: dict) -> "TreeModel":
        try:
            return TreeModel(d["features"], d["left"], d["right"], d["feature"], d["threshold"], d["label"])
        except (KeyError, TypeError) as e:
            raise UserError(f"malformed tree file: {e}") from None

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @staticmethod
    def from_json(text: str) -> "TreeModel":
        try:
            return TreeModel.from_dict(json.loads(text))
        except ValueError as e:
            raise UserError(f"malformed tree file: {e}") from None

    @cached_property
    def _arrays(self) -> tuple[Tensor, Tensor, Tensor, Tensor, int]:
        """The node arrays as tensors, built once (trees have thousands of nodes; predict runs every step):
        children (2 M,) with a leaf its own child on both sides, feature (M,), threshold (M,), label (M,), depth."""
        left, right = torch.tensor(self.left), torch.tensor(self.right)
        node = torch.arange(len(self.left))
        leaf = left < 0
        children = torch.stack([torch.where(leaf, node, left), torch.where(leaf, node, right)], -1).flatten()
        depth, level = 0, torch.zeros(1, dtype=torch.long)
        while bool((left[level] >= 0).any()):  # deepest leaf: the number of descents that reach every leaf
            inner = level[left[level] >= 0]
            level = torch.cat([left[inner], right[inner]])
            depth += 1
        return (children, torch.tensor(self.feature).clamp(min=0), torch.tensor(self.threshold, dtype=torch.float32),
                torch.tensor(self.label), depth)

    def predict(self, feats: FeatureView) -> Tensor:
        """(B, N, N) bool: the tree's decision for every pair (self removed by the caller's mask)."""
        b, n = feats.batch, feats.n_agents
        dev = feats.device
        children, feat, thr, label = (a.to(dev) for a in self._arrays[:4])
        cols = torch.stack([feats[f].expand(b, n, n) for f in self.features], -1).flatten(0, 2)  # (B N N, F)
        node = torch.zeros(cols.shape[0], dtype=torch.long, device=dev)
        # every pair descends the same number of levels: no compaction of the pairs still inside the tree, since
        # a leaf is its own child; four gathers per level beat masking and scattering an active set
        for _ in range(self._arrays[4]):
            x = cols.gather(1, feat[node].unsqueeze(1)).squeeze(1)  # (B N N,) the tested feature of each pair
            node = children[2 * node + (x > thr[node])]
        return label[node].view(b, n, n)


def fit_tree(x: Tensor, y: Tensor, names: list[str], depths: tuple[int, ...], seed: int) -> tuple[TreeModel, dict]:
    """Fit one tree per max depth on 80% of the pairs, keep the most accurate on the other 20%."""
    try:
        from sklearn.tree import DecisionTreeClassifier
    except ImportError:
        raise UserError("the dt baseline needs scikit-learn: pip install 'neurosym[dt]'") from None
    g = torch.Generator().manual_seed(seed)
    perm = torch.randperm(len(y), generator=g)
    cut = int(0.8 * len(y))
    tr, va = perm[:cut], perm[cut:]
    xn, yn = x.numpy(), y.numpy()
    best, scores = None, {}
    for depth in depths:
        clf = DecisionTreeClassifier(max_depth=depth, class_weight="balanced", random_state=seed)
        clf.fit(xn[tr.numpy()], yn[tr.numpy()])
        acc = float((clf.predict(xn[va.numpy()]) == yn[va.numpy()]).mean())
        scores[depth] = acc
        if best is None or acc > scores[best[0]]:
            best = (depth, clf)
    assert best is not None
    t = best[1].tree_
    classes = best[1].classes_
    model = TreeModel(list(names), t.children_left.tolist(), t.children_right.tolist(), t.feature.tolist(),
                      t.threshold.tolist(), [bool(classes[v.argmax()]) for v in t.value[:, 0, :]])
    return model, {"depth": best[0], "validation_accuracy": scores}

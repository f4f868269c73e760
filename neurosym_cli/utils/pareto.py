"""Loss against communication: the non-dominated set of (loss, degree) points and the area it dominates.

Both coordinates are minimised. A point dominates another when it is no worse in both and better in one.
"""

from __future__ import annotations

from typing import Sequence


def pareto_front(points: Sequence[tuple[float, float]]) -> list[int]:
    """Indices of the non-dominated points (duplicates of a front point are all kept), sorted by the first
    coordinate."""
    keep = []
    for i, (a, b) in enumerate(points):
        dominated = any((c <= a and d <= b) and (c < a or d < b) for j, (c, d) in enumerate(points) if j != i)
        if not dominated:
            keep.append(i)
    return sorted(keep, key=lambda i: (points[i][0], points[i][1]))


def dominated_area(points: Sequence[tuple[float, float]], ref: tuple[float, float]) -> float:
    """Area of the region that the points dominate inside the box below ``ref`` (the 2-D hypervolume).
    Points beyond the reference in either coordinate add nothing."""
    inside = sorted((x, y) for x, y in points if x < ref[0] and y < ref[1])
    xs = [x for x, _ in inside] + [ref[0]]
    area, best_y = 0.0, ref[1]
    for k, (x, y) in enumerate(inside):  # sweep along x: the dominated height is ref_y minus the best y so far
        best_y = min(best_y, y)
        area += (xs[k + 1] - x) * (ref[1] - best_y)
    return area

"""RRT-Connect in a box of a weighted Euclidean space, with batched validity checks, then shortcuts.

The planner (Kuffner and LaValle's RRT-Connect) grows one tree from the start and one from the goal. Each round
draws a uniform sample in the box, extends the tree whose turn it is by at most :attr:`RrtSettings.step` towards
it, then pulls the other tree straight at the new node as far as the straight line stays valid; the trees swap
roles; a pull that arrives joins them. An edge is valid when every point on it, :attr:`RrtSettings.resolution`
apart in the metric, is valid; all those points go to the validity function in one batch, so the costly part (the
body's collision and balance checks) runs vectorised. The path found is shortened by shortcuts (a random pair of
points on the path joined straight wherever that edge is valid) and finally by a greedy pass (from each node, the
farthest later node it sees). Everything random comes from the ``numpy`` generator passed in: one seed, one path.

Distances are ``|W (a - b)|`` with per-coordinate weights ``W``: joint angles [rad] weigh 1, other coordinates
(a progress along a segment) what a radian of them is worth.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

Validity = Callable[[np.ndarray], np.ndarray]   # states (N, d) -> valid (N,) bool


@dataclass(frozen=True)
class RrtSettings:
    """How the planner searches: the largest extension [metric units], the spacing of the points checked along an
    edge, the number of samples and the wall-time budget [s], the shortcut attempts."""

    step: float = 0.35
    resolution: float = 0.02
    max_samples: int = 4000
    budget_s: float = 4.0
    shortcuts: int = 60


@dataclass(frozen=True)
class Box:
    """The sampling box (lower, upper) (d,) and the metric's weights (d,)."""

    lower: np.ndarray
    upper: np.ndarray
    weight: np.ndarray

    def distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Weighted distance between states (..., d) and (..., d)."""
        d = (np.asarray(a) - np.asarray(b)) * self.weight
        dist: np.ndarray = np.sqrt(np.sum(d * d, axis=-1))
        return dist


class _Tree:
    """Nodes (grown in a preallocated array) and each node's parent index (-1 for the root)."""

    def __init__(self, root: np.ndarray, capacity: int):
        self.nodes = np.empty((capacity, len(root)))
        self.parent = np.full(capacity, -1, dtype=int)
        self.nodes[0], self.size = root, 1

    def add(self, state: np.ndarray, parent: int) -> int:
        if self.size == len(self.nodes):
            self.nodes = np.vstack([self.nodes, np.empty_like(self.nodes)])
            self.parent = np.concatenate([self.parent, np.full(len(self.parent), -1, dtype=int)])
        self.nodes[self.size], self.parent[self.size] = state, parent
        self.size += 1
        return self.size - 1

    def nearest(self, state: np.ndarray, box: Box) -> int:
        return int(np.argmin(box.distance(self.nodes[:self.size], state)))

    def path_to_root(self, index: int) -> list[np.ndarray]:
        out = []
        while index >= 0:
            out.append(self.nodes[index].copy())
            index = int(self.parent[index])
        return out


def edge_points(a: np.ndarray, b: np.ndarray, box: Box, resolution: float) -> np.ndarray:
    """Points (n + 1, d) from ``a`` to ``b`` (both included), at most ``resolution`` apart in the metric."""
    n = max(1, int(math.ceil(float(box.distance(a, b)) / resolution)))
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    points: np.ndarray = a + t * (b - a)
    return points


def valid_prefix(a: np.ndarray, b: np.ndarray, valid: Validity, box: Box, resolution: float) -> tuple[float, bool]:
    """How far along a -> b [0..1] the edge stays valid (checked in one batch, ``a`` assumed valid), and whether
    it reaches ``b``."""
    points = edge_points(a, b, box, resolution)
    ok = valid(points[1:])
    if ok.all():
        return 1.0, True
    first_bad = int(np.argmin(ok))
    return first_bad / (len(points) - 1), False


def edge_valid(a: np.ndarray, b: np.ndarray, valid: Validity, box: Box, resolution: float) -> bool:
    """Is every point on the straight edge valid."""
    return bool(valid(edge_points(a, b, box, resolution)).all())


def _pull(tree: _Tree, target: np.ndarray, valid: Validity, box: Box, s: RrtSettings) -> tuple[int, bool]:
    """Grow ``tree`` straight at ``target`` from its nearest node while the line is valid (nodes every ``step``);
    the last node added (or the nearest) and whether it reached the target."""
    near = tree.nearest(target, box)
    start = tree.nodes[near].copy()
    reach, arrived = valid_prefix(start, target, valid, box, s.resolution)
    length = float(box.distance(start, target)) * reach
    if not arrived:                                 # stay a checking step short of the first invalid point
        length = max(0.0, length - s.resolution)
    if length <= 0.0:
        return near, False
    direction = (target - start) / max(float(box.distance(start, target)), 1e-12)
    pieces = max(1, int(math.ceil(length / s.step)))
    last = near
    for k in range(1, pieces + 1):
        state = target.copy() if arrived and k == pieces else start + direction * length * k / pieces
        last = tree.add(state, last)
    return last, arrived


def rrt_connect(start: np.ndarray, goal: np.ndarray, valid: Validity, box: Box, rng: np.random.Generator,
                settings: RrtSettings = RrtSettings()) -> list[np.ndarray] | None:
    """A valid piecewise-straight path [start, ..., goal] (states (d,)), or None when the samples or the time budget
    run out first. ``start`` and ``goal`` must be valid."""
    if edge_valid(start, goal, valid, box, settings.resolution):
        return [start.copy(), goal.copy()]
    trees = [_Tree(start, 256), _Tree(goal, 256)]
    deadline = time.monotonic() + settings.budget_s
    for k in range(settings.max_samples):
        if time.monotonic() > deadline:
            return None
        grow, other = trees[k % 2], trees[1 - k % 2]
        sample = box.lower + rng.random(len(start)) * (box.upper - box.lower)
        near = grow.nearest(sample, box)
        gap = float(box.distance(grow.nodes[near], sample))
        toward = sample if gap <= settings.step else (
            grow.nodes[near] + (sample - grow.nodes[near]) * settings.step / gap)
        if not edge_valid(grow.nodes[near], toward, valid, box, settings.resolution):
            continue
        new = grow.add(toward, near)
        last, arrived = _pull(other, grow.nodes[new], valid, box, settings)
        if arrived:
            a, b = grow.path_to_root(new), other.path_to_root(last)[1:]
            path = a[::-1] + b if k % 2 == 0 else b[::-1] + a
            return path
    return None


def shortcut(path: list[np.ndarray], valid: Validity, box: Box, rng: np.random.Generator,
             settings: RrtSettings = RrtSettings()) -> list[np.ndarray]:
    """``path`` shortened: random shortcuts between points on it, then a greedy pass keeping from each node only
    the farthest later node it sees straight."""
    pts = [p.copy() for p in path]
    for _ in range(settings.shortcuts):
        if len(pts) < 3:
            break
        lengths = np.concatenate([[0.0], np.cumsum([box.distance(a, b) for a, b in zip(pts, pts[1:])])])
        u, w = np.sort(rng.random(2) * lengths[-1])
        i, j = int(np.searchsorted(lengths, u, side="right")) - 1, int(np.searchsorted(lengths, w, side="right")) - 1
        if j <= i:
            continue
        pu = pts[i] + (pts[i + 1] - pts[i]) * (u - lengths[i]) / max(lengths[i + 1] - lengths[i], 1e-12)
        pw = pts[j] + (pts[j + 1] - pts[j]) * (w - lengths[j]) / max(lengths[j + 1] - lengths[j], 1e-12)
        if edge_valid(pu, pw, valid, box, settings.resolution):
            pts = pts[:i + 1] + [pu, pw] + pts[j + 1:]
    out, i = [pts[0]], 0
    while i < len(pts) - 1:
        j = len(pts) - 1
        while j > i + 1 and not edge_valid(pts[i], pts[j], valid, box, settings.resolution):
            j -= 1
        out.append(pts[j])
        i = j
    return [p for k, p in enumerate(out) if k == 0 or box.distance(p, out[k - 1]) > 1e-9]

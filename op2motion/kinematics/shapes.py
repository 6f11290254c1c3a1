"""Self-clearance: how far apart the robot's collision shapes are, for a batch of poses on the D-H chain.

The shapes are the spec's ``[[collision]]`` entries, the ones physics simulates, placed by the link attachments of
:mod:`.links`. Pairs are those the physics engines check: shapes on different links that are not parent and child.
Every shape is a *segment swept by a radius* or a *box*:

* sphere: a segment of length zero; cylinder (radius r, length L): a segment of length L - r along its axis, so
  the round caps reach r/2 beyond the flat ends (their rims are missed by at most 0.12 r; 2 mm on a forearm);
* box: exact. Box against segment is the minimum of the box's signed distance along the segment (convex, found by
  sampling the segment in rounds); box against box is the least of each box's twelve edges against the other box, which
  is exact for convex polyhedra (the closest points, or a crossing, always lie on an edge of one of them).

Clearance is the distance between the shapes' surfaces [m], negative when they overlap (then it is the depth of
an edge or segment inside the other box, or of the swept spheres' overlap). A broad phase on bounding spheres skips
exact work where two shapes are more than ``within`` apart (then a segment or edge against a box by the box's
distance to the segment's middle less half its length), and those pairs report that lower bound of the clearance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.kinematics.dh_chain import cached
from op2motion.kinematics.links import attachments
from op2motion.robot.spec import Spec, rpy_matrix
from op2motion.robot.support import Side, Support

RIM_MISS_SHARE = 0.118      # a cylinder's rim lies this share of its radius outside its capsule (sqrt(1.25) - 1)
BROAD_PHASE_M = 0.03        # default: clearances beyond this are reported as lower bounds, not exactly
SAMPLES, ROUNDS = 9, 4      # samples along a segment per round; rounds (the bracket shrinks to (1/4)^4 = 4e-3)
SEGMENT_GRID = np.linspace(0.0, 1.0, SAMPLES)
BOX_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
BOX_EDGES = np.array([(a, b) for a in range(8) for b in range(a + 1, 8)
                      if np.sum(BOX_CORNERS[a] != BOX_CORNERS[b]) == 1])        # (12, 2) corner indices
_EDGE_A, _EDGE_B = BOX_EDGES[:, 0], BOX_EDGES[:, 1]


@dataclass(frozen=True)
class ShapeSet:
    """The spec's collision shapes on the chain of one support foot, and the pairs to check.

    Shape ``k`` rides on chain slot ``slots[k]`` at ``local[k]`` (4, 4); ``half[k]`` is a box's half extents [m]
    (NaN for segments), ``segment[k]`` a segment's end points in the shape frame (2, 3) [m] and ``radius[k]`` its
    radius [m]; ``bound[k]`` the bounding-sphere radius about the shape origin [m].
    """

    links: tuple[str, ...]
    slots: np.ndarray
    local: np.ndarray
    is_box: np.ndarray
    half: np.ndarray
    segment: np.ndarray
    radius: np.ndarray
    bound: np.ndarray
    pairs: np.ndarray                       # (P, 2) shape indices
    capsule_pairs: np.ndarray               # indices into pairs of segment-against-segment pairs
    box_box: np.ndarray                     # (B, 3): (pair, box whose edges are tried, other box), both ways round
    segment_box: np.ndarray                 # (G, 3): (pair, segment shape, box)

    def pair_names(self) -> list[tuple[str, str]]:
        """The link names of each pair."""
        return [(self.links[a], self.links[b]) for a, b in self.pairs]

    def approximation_m(self) -> tuple[np.ndarray, np.ndarray]:
        """How much more (P,) and how much less (P,) than the exact distance a pair's clearance may be [m]: the rims
        of its cylinders (:data:`RIM_MISS_SHARE` of each one's radius) and their round caps (half a radius each)."""
        cylinder = ~self.is_box & (np.abs(self.segment[:, 1, 2] - self.segment[:, 0, 2]) > 0.0)
        r = np.where(cylinder, self.radius, 0.0)
        per_pair = r[self.pairs[:, 0]] + r[self.pairs[:, 1]]
        return RIM_MISS_SHARE * per_pair, 0.5 * per_pair


def shape_set(spec: Spec, support: Support | Side) -> ShapeSet:
    """The shapes and pairs of ``spec`` on the chain rooted at ``support`` (cached)."""
    return cached("shapes", spec, support, _build)


def _build(spec: Spec, support: Support | Side) -> ShapeSet:
    attached = attachments(spec, support)
    links, slots, local, is_box, half, segment, radius, bound = [], [], [], [], [], [], [], []
    for c in spec.collisions:
        at = attached[c.link]
        t = np.eye(4)
        t[:3, :3], t[:3, 3] = rpy_matrix(c.origin_rpy), c.origin_xyz
        links.append(c.link)
        slots.append(at.slot)
        local.append(at.local @ t)
        box = c.shape == "box"
        is_box.append(box)
        h = np.asarray(c.size, dtype=float) / 2 if box else np.full(3, np.nan)
        half.append(h)
        r = 0.0 if box else c.size[0]
        reach = max((c.size[1] - r) / 2, 0.0) if c.shape == "cylinder" else 0.0
        segment.append([[0.0, 0.0, -reach], [0.0, 0.0, reach]])
        radius.append(r)
        bound.append(float(np.linalg.norm(h)) if box else reach + r)
    parents = {j.child: j.parent for j in spec.joints}
    pairs = [(a, b) for a in range(len(links)) for b in range(a + 1, len(links))
             if links[a] != links[b] and parents.get(links[a]) != links[b] and parents.get(links[b]) != links[a]]
    capsule_pairs, box_box, segment_box = [], [], []
    for p, (a, b) in enumerate(pairs):
        if is_box[a] and is_box[b]:
            box_box += [(p, a, b), (p, b, a)]
        elif is_box[a] or is_box[b]:
            segment_box.append((p, b, a) if is_box[a] else (p, a, b))
        else:
            capsule_pairs.append(p)
    return ShapeSet(tuple(links), np.array(slots), np.array(local), np.array(is_box), np.array(half),
                    np.array(segment), np.array(radius), np.array(bound), np.array(pairs, dtype=int).reshape(-1, 2),
                    np.array(capsule_pairs, dtype=int), np.array(box_box, dtype=int).reshape(-1, 3),
                    np.array(segment_box, dtype=int).reshape(-1, 3))


def _box_distance(x: np.ndarray, y: np.ndarray, z: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Signed distance [m] of points (x, y, z each (K,), in a box's frame) to the box of half extents (3, K)."""
    qx: np.ndarray = np.abs(x)                            # in place from here: fewer temporaries, less time
    qy, qz = np.abs(y), np.abs(z)
    qx -= half[0]
    qy -= half[1]
    qz -= half[2]
    inside = np.maximum(qx, qy)
    np.maximum(inside, qz, out=inside)
    np.minimum(inside, 0.0, out=inside)
    for q in (qx, qy, qz):
        np.maximum(q, 0.0, out=q)
        q *= q
    qx += qy
    qx += qz
    np.sqrt(qx, out=qx)
    qx += inside
    return qx


def _segment_box(a: np.ndarray, b: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Least signed distance [m] from segments a-b (3, K) to boxes of half extents (3, K) (in the box frames).

    The distance along a segment is convex, so the least of :data:`SAMPLES` evenly spaced samples brackets the
    minimum between its neighbours; each round samples that bracket again."""
    d = b - a
    lo, width = np.zeros(a.shape[1]), np.ones(a.shape[1])
    best = np.full(a.shape[1], np.inf)
    columns = np.arange(a.shape[1])
    for _ in range(ROUNDS):
        t = lo + width * SEGMENT_GRID[:, None]                                      # (SAMPLES, K)
        f = _box_distance(a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2], half)
        i = np.argmin(f, axis=0)
        best = np.minimum(best, f[i, columns])
        step = width / (SAMPLES - 1)
        lo = np.clip(lo + (i - 1) * step, 0.0, 1.0 - 2.0 * step)
        width = 2.0 * step
    return best


def _segment_segment(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distance [m] between segments p1-q1 and p2-q2, (K, 3) each (closest points clamped to both segments)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e = np.sum(d1 * d1, axis=-1), np.sum(d2 * d2, axis=-1)
    b, c, f = np.sum(d1 * d2, axis=-1), np.sum(d1 * r, axis=-1), np.sum(d2 * r, axis=-1)
    denom = a * e - b * b
    tiny = 1e-15
    s = np.where(denom > tiny, np.clip((b * f - c * e) / np.maximum(denom, tiny), 0.0, 1.0), 0.0)
    t = np.where(e > tiny, (b * s + f) / np.maximum(e, tiny), 0.0)
    s = np.where(t < 0.0, np.where(a > tiny, np.clip(-c / np.maximum(a, tiny), 0.0, 1.0), 0.0), s)
    s = np.where(t > 1.0, np.where(a > tiny, np.clip((b - c) / np.maximum(a, tiny), 0.0, 1.0), 0.0), s)
    t = np.clip(t, 0.0, 1.0)
    gap = (p1 + s[:, None] * d1) - (p2 + t[:, None] * d2)
    dist: np.ndarray = np.sqrt(np.sum(gap * gap, axis=-1))
    return dist


def shape_frames(frames: np.ndarray, shapes: ShapeSet) -> np.ndarray:
    """Every shape's frame (S, m, 4, 4) in the support-sole frame, from the chain frames (slots, m, 4, 4)."""
    world: np.ndarray = frames[shapes.slots] @ shapes.local[:, None]
    return world


def clearances(frames: np.ndarray, shapes: ShapeSet, within: float = BROAD_PHASE_M) -> np.ndarray:
    """Clearance [m] of every pair (P, m) for chain frames (slots, m, 4, 4), negative where shapes overlap; exact
    below ``within`` [m], a lower bound above it."""
    world = shape_frames(frames, shapes)                                     # (S, m, 4, 4)
    rot, origin = np.ascontiguousarray(world[..., :3, :3]), np.ascontiguousarray(world[..., :3, 3])
    first, second = shapes.pairs[:, 0], shapes.pairs[:, 1]
    gap = origin[first] - origin[second]
    out = np.sqrt(np.sum(gap * gap, axis=-1)) - (shapes.bound[first] + shapes.bound[second])[:, None]  # broad phase
    near = out < within
    exact = np.full(out.shape, np.inf)
    if len(shapes.capsule_pairs):
        cp = shapes.capsule_pairs
        both = np.concatenate([shapes.pairs[cp, 0], shapes.pairs[cp, 1]])               # (2C,) shapes
        ends = np.einsum("smij,sej->smei", rot[both], shapes.segment[both]) + origin[both][:, :, None]
        c = len(cp)
        flat = [ends[rows, :, e].reshape(-1, 3) for rows in (slice(0, c), slice(c, 2 * c)) for e in (0, 1)]
        dist = _segment_segment(flat[0], flat[1], flat[2], flat[3]).reshape(c, -1)
        exact[cp] = dist - (shapes.radius[shapes.pairs[cp, 0]] + shapes.radius[shapes.pairs[cp, 1]])[:, None]
    m = frames.shape[1]
    flat_rot, flat_origin = rot.reshape(-1, 3, 3), origin.reshape(-1, 3)

    def into_box(src: np.ndarray, box: np.ndarray, pose: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Points (I, n, 3) in the frames of shapes ``src`` into the frames of shapes ``box``, at ``pose``."""
        at_src, at_box = src * m + pose, box * m + pose                     # np.take: the fast gather
        r_src, r_box = np.take(flat_rot, at_src, axis=0), np.take(flat_rot, at_box, axis=0)
        shift = np.take(flat_origin, at_src, axis=0) - np.take(flat_origin, at_box, axis=0)
        local: np.ndarray = np.einsum("kji,knj->kni", r_box, np.einsum("kij,knj->kni", r_src, points) + shift[:, None])
        return local

    pieces = []                                   # (pair, pose, ends a and b (K, 3), box half extents, radius)
    live, pose = np.nonzero(near[shapes.box_box[:, 0]])                      # box-box: the 8 corners, then edges
    if len(live):
        pair, src, box = shapes.box_box[live].T
        corners = into_box(src, box, pose, BOX_CORNERS[None] * shapes.half[src][:, None])       # (I, 8, 3)
        n = len(BOX_EDGES)
        pieces.append((np.repeat(pair, n), np.repeat(pose, n), corners[:, _EDGE_A].reshape(-1, 3),
                       corners[:, _EDGE_B].reshape(-1, 3), np.repeat(shapes.half[box], n, axis=0),
                       np.zeros(n * len(pair))))
    live, pose = np.nonzero(near[shapes.segment_box[:, 0]])
    if len(live):
        pair, src, box = shapes.segment_box[live].T
        ends = into_box(src, box, pose, shapes.segment[src])                                # (I, 2, 3)
        pieces.append((pair, pose, ends[:, 0], ends[:, 1], shapes.half[box], shapes.radius[src]))
    if pieces:
        pair, pose, a, b, half, rim = (np.concatenate(x) for x in zip(*pieces))
        a, b, half = a.T, b.T, half.T                                                        # (3, K)
        outside = np.maximum(np.maximum(np.minimum(a, b) - half, -half - np.maximum(a, b)), 0.0)
        value = np.sqrt(np.sum(outside * outside, axis=0)) - rim      # the segment's bounding box against the box
        close = value < within
        value[close] = _segment_box(a[:, close], b[:, close], half[:, close]) - rim[close]
        np.minimum.at(exact, (pair, pose), value)
    return np.where(np.isfinite(exact), exact, out)


def self_clearance(frames: np.ndarray, shapes: ShapeSet) -> tuple[np.ndarray, np.ndarray]:
    """The least clearance over all pairs (m,) [m] and the pair it belongs to (m,) (index into ``shapes.pairs``)."""
    every = clearances(frames, shapes)
    worst = np.argmin(every, axis=0)
    return every[worst, np.arange(every.shape[1])], worst

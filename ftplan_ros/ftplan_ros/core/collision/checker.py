"""Batched clearances of the arm: its links from the obstacles, and pairs of links apart.

The clearance of a configuration has one column per *channel*: each collision shape of
a moving link against every obstacle, then each pair of shapes of every self-collision
pair of links. A channel's lever arms (`CollisionChecker.lever_arms`) bound how fast its
distance can shrink as the joints turn, which is what the certificate (verification.py)
needs: per shape rather than per link, so that a shape close to a joint's axis, which
that joint hardly moves, is not held to the speed of the far end of its link.

Distances come in tiers, cheapest first:

1. Exact and vectorised over thousands of configurations wherever one side is a sphere
   (the signed distance of the other shape at the sphere's centre, minus its radius):
   the paper's disks against capsule links, sphere obstacles against any link.
2. For other pairs (a box or cylinder obstacle against a box, cylinder or capsule link;
   two such links) the bounding sphere of the link shape gives a lower bound at the
   same price.
3. Where that bound is below what the caller `needed`, python-fcl measures the pair.
   Its GJK can report distances centimetres too long, so fcl only gives a direction:
   the clearance is the shapes' separation along the line joining fcl's nearest points,
   from their support functions (geometry.separation), a lower bound whatever the
   direction. On contact the answer is 0; fcl needs capsules of radius >= 1 cm, so a
   thinner capsule also reads 0 within 1 cm of an obstacle.

A mesh link is measured through its cover (model/cover.py: convex pieces whose union
holds every point of the mesh; a convex mesh is one piece, its own hull). Its tiers 1-2
are the least GJK bound over the pieces (convex_kernels.py). A piece that bulges less
than `cover.TIGHT_PADDING` (1 mm; under half a millimetre for each of the Panda's
meshes) beyond the mesh is taken for the mesh itself, as a primitive model's padding
is: its distance counts as exact. Tier 3 measures the triangles held by the other
pieces, exactly.

Obstacles farther from the arm's reach than `CULL_DISTANCE` are dropped; a channel's
clearance is then capped at the nearest dropped obstacle's lower bound, so it stays a
lower bound. A touching or penetrating channel has a clearance <= 0 (tier 1: minus
the depth; tiers 2-3: 0).
"""

from __future__ import annotations

from collections.abc import Sequence

import fcl
import numpy as np

from ..model.geometry import Shape, fcl_geometry, rotation_from_rpy, separation, signed_distance
from ..model.robot import LinkShape, PlanarChain, Robot
from ..model.scene import Obstacle
from .convex_kernels import (
    HULL,
    cover_obstacle_distances,
    cover_pair_distances,
    refined_distance,
)
from .distance_kernels import (
    CODES,
    MESH,
    enclosing_capsule,
    exact_pairs,
    obstacle_distances,
    pair_distances,
    pair_modes,
    planar_link_clearances,
    shape_poses,
)

CULL_DISTANCE = 1.0  # [m] obstacles at least this far beyond the arm's reach are dropped
_CHUNK_ENTRIES = 1 << 20  # configurations x shapes x obstacles per batch
_FCL_PADDING = 1e-2  # [m] thinnest capsule radius handed to fcl
_EXACT_WITH_SPHERE = ('sphere', 'box', 'cylinder', 'capsule')  # shapes with a signed distance


def obstacle_shape(obstacle: Obstacle) -> Shape:
    """Return the geometry of an obstacle, in its own frame (centre `center`, turned by `rpy`)."""
    if obstacle.shape == 'sphere':
        return Shape('sphere', radius=obstacle.radius)
    if obstacle.shape == 'box':
        return Shape('box', size=tuple(obstacle.size))
    return Shape('cylinder', radius=obstacle.radius, length=obstacle.length)


def shape_parameters(shape: Shape) -> np.ndarray:
    """Return a shape's three parameters for the compiled distances (distance_kernels.py) [m]."""
    if shape.kind == 'sphere':
        return np.array([shape.radius, 0.0, 0.0])
    if shape.kind == 'box':
        return 0.5 * np.asarray(shape.size, dtype=float)
    if shape.kind in ('cylinder', 'capsule'):
        return np.array([shape.radius, 0.5 * shape.length, 0.0])
    return np.zeros(3)


def piece_table(shapes: Sequence[Shape]) -> tuple[tuple, np.ndarray]:
    """Shapes as convex pieces for convex_kernels.py: a mesh by its cover, any other whole.

    Returns the table (convex_kernels.py says its layout) and piece_start (S+1,): shape s
    is pieces piece_start[s]..piece_start[s+1]-1.
    """
    kinds, parameters, bounds, vertices, triangles, exact, starts = [], [], [], [], [], [], [0]
    for shape in shapes:
        if shape.kind == 'mesh':
            cover = shape.cover
            for piece, held, whole in zip(cover.pieces, cover.triangles, cover.tight,
                                          strict=True):
                centre = 0.5 * (piece.min(axis=0) + piece.max(axis=0))
                kinds.append(HULL)
                parameters.append(np.zeros(3))
                bounds.append(np.append(centre, np.linalg.norm(piece - centre, axis=1).max()))
                vertices.append(piece)
                triangles.append(held)
                exact.append(bool(whole))
        else:
            kinds.append(CODES[shape.kind])
            parameters.append(shape_parameters(shape))
            bounds.append(np.append(*shape.bounding_sphere()))
            vertices.append(np.zeros((0, 3)))
            triangles.append(np.zeros((0, 3, 3)))
            exact.append(True)
        starts.append(len(kinds))
    table = (np.array(kinds, dtype=np.int64), np.array(parameters, dtype=float).reshape(-1, 3),
             np.array(bounds, dtype=float).reshape(-1, 4), _starts(vertices),
             np.ascontiguousarray(np.concatenate(vertices + [np.zeros((0, 3))]), dtype=float),
             _starts(triangles),
             np.ascontiguousarray(np.concatenate(triangles + [np.zeros((0, 3, 3))]), dtype=float),
             np.array(exact, dtype=bool))
    return table, np.array(starts, dtype=np.int64)


def _starts(arrays: list[np.ndarray]) -> np.ndarray:
    """Where each of the arrays starts once they are concatenated, and where the last ends."""
    return np.cumsum([0] + [len(array) for array in arrays]).astype(np.int64)


class _Shapes:
    """Shapes as arrays for the compiled distances.

    Kind codes, parameters, bounding spheres (S, 4) and enclosing capsules (S, 7), in the
    shapes' own frames; the shapes as convex pieces (`piece_table`), whether each is a
    covered mesh (S,) and whether GJK measures it exactly (S,).
    """

    def __init__(self, shapes: Sequence[Shape]):
        self.shapes = list(shapes)
        self.kinds = np.array([CODES[shape.kind] for shape in shapes], dtype=np.int64)
        self.parameters = np.array([shape_parameters(shape) for shape in shapes]).reshape(-1, 3)
        self.bounds = np.array([np.append(*shape.bounding_sphere()) for shape in shapes],
                               dtype=float).reshape(-1, 4)
        self.capsules = np.array([enclosing_capsule(kind, parameters, bound[:3], bound[3])
                                  for kind, parameters, bound in zip(
                                      self.kinds, self.parameters, self.bounds, strict=True)],
                                 dtype=float).reshape(-1, 7)
        self.pieces, self.piece_start = piece_table(self.shapes)
        self.covered = self.kinds == MESH
        self.exact = np.array([self.pieces[7][start:end].all() for start, end in zip(
            self.piece_start[:-1], self.piece_start[1:], strict=True)], dtype=bool)


class _Obstacles(_Shapes):
    """Obstacles as posed shapes, and their python-fcl objects on demand."""

    def __init__(self, obstacles: Sequence[Obstacle]):
        self.items = list(obstacles)
        super().__init__([obstacle_shape(ob) for ob in self.items])
        self.rotations = np.array([rotation_from_rpy(ob.rpy) for ob in self.items],
                                  dtype=float).reshape(-1, 3, 3)
        self.centres = np.array([ob.center for ob in self.items], dtype=float).reshape(-1, 3)
        self.frames = np.zeros((len(self.items), 4, 4))
        self.frames[:, :3, :3], self.frames[:, :3, 3], self.frames[:, 3, 3] = \
            self.rotations, self.centres, 1.0
        self.world_bounds = np.concatenate(
            [np.einsum('pij,pj->pi', self.rotations, self.bounds[:, :3]) + self.centres,
             self.bounds[:, 3:]], axis=1)
        self._fcl: list[fcl.CollisionObject] | None = None

    def __len__(self) -> int:
        return len(self.items)

    def fcl_objects(self) -> list[fcl.CollisionObject]:
        """Return the obstacles as posed python-fcl objects (built on first use)."""
        if self._fcl is None:
            self._fcl = [fcl.CollisionObject(fcl_geometry(shape), fcl.Transform(r, c))
                         for shape, r, c in zip(self.shapes, self.rotations, self.centres,
                                                strict=True)]
        return self._fcl

    def subset(self, keep: np.ndarray) -> _Obstacles:
        """Return the obstacles where `keep` (P,) is True."""
        return _Obstacles([ob for ob, kept in zip(self.items, keep, strict=True) if kept])


class CollisionChecker:
    """Clearance [m] of every channel (see the module docstring).

    `backend` 'auto' uses the tiers; 'fcl' measures every pair that is not exact in tier 1
    with fcl, whatever the caller needs, for cross-checks.
    """

    def __init__(self, robot: Robot, obstacles: Sequence[Obstacle], backend: str = 'auto'):
        if backend not in ('auto', 'fcl'):
            raise ValueError(f'unknown collision backend {backend!r}')
        self.robot = robot
        self.obstacles = tuple(obstacles)
        self.backend = backend
        self.checks = 0  # configurations whose clearance was computed
        # Moving shapes first, then the base's (posed by their placement alone).
        items = sorted(robot.collision_shapes, key=lambda item: item.link == 0)
        self._items = items
        self._shapes = _Shapes([item.shape for item in items])
        self._links = np.array([item.link for item in items], dtype=np.int64)
        self._placements = np.array([item.placement for item in items]).reshape(-1, 4, 4)
        self._moving = int(np.count_nonzero(self._links != 0))
        self.pairs = tuple(robot.self_collision_pairs)
        self._lever_arms = None
        exempt = robot.exempt_urdf_pairs
        self._shape_pairs = np.array(
            [(s, t) for a, b in self.pairs for s in np.flatnonzero(self._links == a)
             for t in np.flatnonzero(self._links == b)
             if frozenset((items[s].urdf_link, items[t].urdf_link)) not in exempt],
            dtype=np.int64).reshape(-1, 2)
        shapes = self._shapes
        first, second = (self._shape_pairs[:, k] for k in (0, 1))
        # Pairs with a mesh go to convex_kernels.py; exact there when both are (GJK).
        self._covered_pairs = shapes.covered[first] | shapes.covered[second]
        self._pair_modes = pair_modes(shapes.kinds[first], shapes.kinds[second])
        self._pair_exact = np.where(self._covered_pairs,
                                    shapes.exact[first] & shapes.exact[second],
                                    exact_pairs(shapes.kinds[first], shapes.kinds[second]))
        self._fcl_shapes = [None if shape.kind == 'mesh' else
                            fcl.CollisionObject(fcl_geometry(shape, _FCL_PADDING))
                            for shape in shapes.shapes]
        self._obstacles, self._cap = self._cull(_Obstacles(self.obstacles))
        moving = np.arange(self._moving)
        self._plain = moving[~shapes.covered[moving]]
        self._covered = moving[shapes.covered[moving]]
        kinds = shapes.kinds[moving, None], self._obstacles.kinds[None, :]
        self._modes = pair_modes(*kinds)[self._plain]
        self._exact = np.where(shapes.covered[moving, None], shapes.exact[moving, None],
                               exact_pairs(*kinds))
        self.planar_disks = self._planar_disks()

    @property
    def n_channels(self) -> int:
        """Number of clearance columns: moving shapes, then shape pairs."""
        return self._moving + len(self._shape_pairs)

    @property
    def channel_names(self) -> list[str]:
        """Say what each column measures, e.g. 'link3[0]' or 'link1[0] / link5[2]'."""
        names = [f'{self.robot.link_names[j]}[{np.count_nonzero(self._links[:k] == j)}]'
                 for k, j in enumerate(self._links)]
        return names[:self._moving] + [f'{names[s]} / {names[t]}' for s, t in self._shape_pairs]

    @property
    def channel_links(self) -> np.ndarray:
        """(C, 2) the link of each channel's shape (and -1), or the two links of a pair."""
        moving = np.stack([self._links[:self._moving], np.full(self._moving, -1)], axis=1)
        return np.concatenate([moving, self._links[self._shape_pairs]]).reshape(-1, 2)

    def lever_arms(self) -> np.ndarray:
        """(C, n) [m]: channel c's clearance changes by at most Σ_a arms[c, a] |Δθ_a|.

        A shape moves at most its link's frame lever arm plus its extent from the link's
        origin (`Robot.frame_lever_arms`); for spheres and capsules, whose distances are
        their cores' minus the radius, the extent of the core. For a pair of shapes on
        links a < b, only joints that turn b and not a change the distance: joints
        a..b-1, with the arms of b's shape. Computed once (the shapes are fixed); each
        caller gets its own copy, so no caller can change what certification relies on.
        """
        if self._lever_arms is None:
            self._lever_arms = self._compute_lever_arms()
        return self._lever_arms.copy()

    def _compute_lever_arms(self) -> np.ndarray:
        frame = self.robot.frame_lever_arms()
        n = self.robot.n_joints
        turns = self._turns()
        shape_arms = np.zeros((len(self._items), n))
        for k, (item, link) in enumerate(zip(self._items, self._links, strict=True)):
            shape_arms[k] = np.where(turns[link], frame[link] + _extent(item), 0.0)
        rows = [shape_arms[:self._moving]]
        for s, t in self._shape_pairs:
            a, b = self._links[s], self._links[t]
            rows.append(np.where(turns[b] & ~turns[a], shape_arms[t], 0.0)[None, :])
        return np.concatenate(rows).reshape(-1, n)

    def _turns(self) -> np.ndarray:
        """(L, n) bool: whether joint a turns link j (`Robot.joint_chain_index`)."""
        chain = np.asarray(self.robot.joint_chain_index)
        links = len(self.robot.link_names)
        return chain[None, :] < np.arange(links)[:, None]

    def clearance(self, thetas: np.ndarray, needed: np.ndarray | float = np.inf,
                  refine: bool = True) -> np.ndarray:
        """Return clearance (N, C) [m] of configurations (N, n) [rad].

        Entries are exact wherever they are below `needed` (scalar or (N, C)) and below the
        cap of the culled obstacles (more than `CULL_DISTANCE` beyond the arm's reach);
        above either they may be lower bounds that are still >= the lesser, which is all a
        caller asking "is it at least this clear?" must know. Without `refine`, tier 3 is
        skipped: every entry is then a lower bound (a cheap screen), exact only where tiers
        1-2 are.
        """
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        self.checks += len(thetas)
        needed = np.broadcast_to(np.asarray(needed, dtype=float), (len(thetas), self.n_channels))
        if self.planar_disks is not None:  # exact in one compiled pass: no chunks, no tiers
            *arrays, cap = self.planar_disks
            # Writable too: numba compiles a kernel per array flag, and the warm-up loads one.
            clearance = planar_link_clearances(*arrays, np.require(thetas, requirements='CW'))
            return np.minimum(clearance, cap, out=clearance)
        out = np.full((len(thetas), self.n_channels), np.inf)
        if self.n_channels == 0 or len(thetas) == 0:
            return out
        chunk = max(16, _CHUNK_ENTRIES // max(1, len(self._obstacles) * len(self._items)))
        for k in range(0, len(thetas), chunk):
            block = slice(k, k + chunk)
            out[block] = self._clearance_block(thetas[block], needed[block], refine)
        return out

    def min_clearance(self, thetas: np.ndarray, needed: float = np.inf,
                      refine: bool = True) -> np.ndarray:
        """Smallest clearance (N,) [m] over all channels (see `clearance`); NaN stays NaN."""
        smallest = np.full(len(np.atleast_2d(thetas)), np.inf)
        # Column by column: numpy's min along short rows is ten times slower.
        for column in self.clearance(thetas, needed, refine).T:
            np.minimum(smallest, column, out=smallest)
        return smallest

    def base_clearance(self) -> np.ndarray:
        """Distance (P,) [m] from the robot's base geometry to each obstacle (<= 0: touching)."""
        out = np.full(len(self.obstacles), np.inf)
        everything, shapes = _Obstacles(self.obstacles), self._shapes
        for s in range(self._moving, len(self._items)):
            item, start = self._items[s], shapes.piece_start
            pose = (item.placement[:3, :3], item.placement[:3, 3])
            for p, (shape, rotation, centre) in enumerate(zip(
                    everything.shapes, everything.rotations, everything.centres, strict=True)):
                distance = refined_distance(
                    shapes.pieces, start[s], start[s + 1], item.placement, everything.pieces, p,
                    p + 1, everything.frames[p]) if shapes.covered[s] else \
                    _pair_distance(item.shape, pose, shape, (rotation, centre))
                out[p] = min(out[p], distance)
        return out

    # Tiers --------------------------------------------------------------------------

    def _planar_disks(self) -> tuple | None:
        """Return the planar fast path's arrays, or None where it does not apply.

        It applies to a planar chain (a capsule per link, no self-collision pairs) among
        spheres: tier 1 is then exact, and `planar_link_clearances` computes it from the
        joint angles without posing frames. The arrays are its arguments but the
        configurations: link lengths (n,) [m], link radius [m], the kept spheres' centres
        (P, 3) [m] and radii (P,) [m]; then the cap of the culled ones [m] (`_cull`).
        Channel k is link k + 1.
        """
        robot = self.robot
        if (self.backend != 'auto' or not isinstance(robot, PlanarChain)
                or len(self._shape_pairs) or np.any(self._obstacles.kinds != CODES['sphere'])):
            return None
        return (robot.kernel_parameters, float(robot.link_radius),
                np.ascontiguousarray(self._obstacles.centres).reshape(-1, 3),
                np.ascontiguousarray(self._obstacles.parameters[:, 0]), float(self._cap))

    def _clearance_block(self, thetas: np.ndarray, needed: np.ndarray, refine: bool,
                         ) -> np.ndarray:
        frames = np.ascontiguousarray(self.robot.link_frames(thetas))  # (N, L, 4, 4)
        poses = shape_poses(frames, self._links, self._placements)  # (N, S, 4, 4)
        out = np.full((len(thetas), self.n_channels), np.inf)
        moving = self._moving
        if len(self._obstacles):
            out[:, :moving] = self._obstacle_channels(poses, needed[:, :moving], refine)
        out[:, :moving] = np.minimum(out[:, :moving], self._cap)
        if len(self._shape_pairs):
            out[:, moving:] = self._pair_channels(poses, needed[:, moving:], refine)
        # A shape placed by a frame that is not finite reads NaN, even with no obstacle near
        # (its position is then not finite either: 0 * NaN is NaN).
        placed = np.isfinite(poses[:, :, :3, 3])  # (N, S, 3)
        if not placed.all():
            placed = placed[..., 0] & placed[..., 1] & placed[..., 2]
            out[:, :moving][~placed[:, :moving]] = np.nan
            first, second = self._shape_pairs.T
            out[:, moving:][~(placed[:, first] & placed[:, second])] = np.nan
        return out

    def _obstacle_channels(self, poses: np.ndarray, needed: np.ndarray, refine: bool,
                           ) -> np.ndarray:
        """Tiers 1-3 for every moving shape against the kept obstacles: (N, S)."""
        shapes, obstacles = self._shapes, self._obstacles
        if self.backend == 'fcl':
            needed = np.full_like(needed, np.inf)
        distance = np.empty(needed.shape + (len(obstacles),))  # (N, S, P)
        plain, covered = self._plain, self._covered
        if len(plain):
            distance[:, plain] = obstacle_distances(
                poses if not len(covered) else np.ascontiguousarray(poses[:, plain]),
                shapes.kinds[plain], shapes.parameters[plain], shapes.bounds[plain],
                shapes.capsules[plain], obstacles.kinds, obstacles.parameters, obstacles.frames,
                obstacles.world_bounds, obstacles.capsules, self._modes,
                np.ascontiguousarray(needed[:, plain]))
        if len(covered):
            distance[:, covered] = cover_obstacle_distances(
                poses, covered, shapes.piece_start, shapes.pieces, obstacles.frames,
                obstacles.pieces, np.ascontiguousarray(needed[:, covered]))
        count, shape_count, obstacle_count = distance.shape

        def measure(n: int, entry: int) -> float:
            s, p = divmod(entry, obstacle_count)
            if shapes.covered[s]:
                return refined_distance(shapes.pieces, shapes.piece_start[s],
                                        shapes.piece_start[s + 1], poses[n, s],
                                        obstacles.pieces, p, p + 1, obstacles.frames[p])
            return _certified_pose(self._fcl_shapes[s], shapes.shapes[s], poses[n, s],
                                   obstacles, p)

        return _channel_minima(distance.reshape(count, shape_count * obstacle_count),
                               self._exact.ravel(),
                               np.repeat(np.arange(shape_count), obstacle_count),
                               needed if refine else np.full_like(needed, -np.inf), measure,
                               self.backend == 'fcl')

    def _pair_channels(self, poses: np.ndarray, needed: np.ndarray, refine: bool,
                       ) -> np.ndarray:
        """Tiers 1-3 for every shape pair of the self-collision pairs: (N, Q)."""
        shapes, pairs, covered = self._shapes, self._shape_pairs, self._covered_pairs
        if self.backend == 'fcl':
            needed = np.full_like(needed, np.inf)
        distance = np.empty(needed.shape)
        if not covered.all():
            distance[:, ~covered] = pair_distances(
                poses, shapes.kinds, shapes.parameters, shapes.bounds, shapes.capsules,
                pairs[~covered], self._pair_modes[~covered],
                np.ascontiguousarray(needed[:, ~covered]))
        if covered.any():
            distance[:, covered] = cover_pair_distances(
                poses, pairs[covered], shapes.piece_start, shapes.pieces,
                np.ascontiguousarray(needed[:, covered]))

        def measure(n: int, q: int) -> float:
            a, b = pairs[q]
            if covered[q]:
                start = shapes.piece_start
                return refined_distance(shapes.pieces, start[a], start[a + 1], poses[n, a],
                                        shapes.pieces, start[b], start[b + 1], poses[n, b])
            return _pair_distance(shapes.shapes[a], (poses[n, a, :3, :3], poses[n, a, :3, 3]),
                                  shapes.shapes[b], (poses[n, b, :3, :3], poses[n, b, :3, 3]))

        return _channel_minima(distance, self._pair_exact, np.arange(len(pairs)),
                               needed if refine else np.full_like(needed, -np.inf), measure,
                               self.backend == 'fcl')

    def _cull(self, obstacles: _Obstacles) -> tuple[_Obstacles, float]:
        """Drop obstacles beyond the arm's reach + CULL_DISTANCE; return the kept and the cap."""
        if not len(obstacles) or not self._moving:
            return obstacles, np.inf
        # Every moving shape a joint turns lies within its arm from the first joint's origin
        # (a sphere's or capsule's arm reaches its core: its radius goes on top); the others
        # stand still, as far from it as they are at any configuration.
        frames = self.robot.link_frames(np.zeros(self.robot.n_joints))
        origin = frames[int(self.robot.joint_chain_index[0]) + 1, :3, 3]
        reaches = self.lever_arms()[:self._moving, 0] + np.array(
            [item.shape.radius if item.shape.kind in ('sphere', 'capsule') else 0.0
             for item in self._items[:self._moving]])
        for k in np.flatnonzero(~self._turns()[self._links[:self._moving], 0]):
            centre, radius = self._items[k].shape.bounding_sphere()
            pose = frames[self._links[k]] @ self._items[k].placement
            reaches[k] = np.linalg.norm(pose[:3, :3] @ centre + pose[:3, 3] - origin) + radius
        reach = float(reaches.max()) + 1e-9
        probe = _Shapes([Shape('sphere', radius=reach)])
        pose = np.eye(4)
        pose[:3, 3] = origin
        lower = obstacle_distances(
            pose[None, None], probe.kinds, probe.parameters, probe.bounds, probe.capsules,
            obstacles.kinds, obstacles.parameters, obstacles.frames, obstacles.world_bounds,
            obstacles.capsules, pair_modes(probe.kinds[:, None], obstacles.kinds[None, :]),
            np.full((1, 1), np.inf))[0, 0]
        far = lower > CULL_DISTANCE
        if not far.any():
            return obstacles, np.inf
        return obstacles.subset(~far), float(lower[far].min())


def _extent(item: LinkShape) -> float:
    """Return how far [m] a shape (a sphere's or capsule's core) reaches from its link's origin.

    A mesh's points are blends of its vertices: the farthest is a vertex.
    """
    shape, placement = item.shape, item.placement
    if shape.kind in ('sphere', 'capsule'):
        half = 0.5 * shape.length if shape.kind == 'capsule' else 0.0
        ends = placement[:3, 3] + np.outer([-half, half], placement[:3, 2])
        return float(np.linalg.norm(ends, axis=1).max())
    if shape.kind == 'mesh':
        return float(np.linalg.norm(shape.vertices @ placement[:3, :3].T + placement[:3, 3],
                                    axis=1).max())
    centre, radius = shape.bounding_sphere()
    return float(np.linalg.norm(placement[:3, :3] @ centre + placement[:3, 3])) + radius


def _channel_minima(bounds: np.ndarray, exact: np.ndarray, channel_of: np.ndarray,
                    needed: np.ndarray, measure, everything: bool) -> np.ndarray:
    """Each channel's smallest distance (N, C) [m] from its entries' tier-1/2 values.

    `bounds` (N, E) are exact where `exact` (E,) says so and lower bounds elsewhere;
    entry e belongs to channel `channel_of[e]`. Where a channel's smallest value is below
    its `needed` (N, C), its loose entries are measured (`measure(n, e)`, tier 3) from the
    lowest bound up, until the next bound is no lower than the best distance so far
    (branch and bound); `everything` measures every loose entry.
    """
    count, channels = needed.shape
    members = [np.flatnonzero(channel_of == c) for c in range(channels)]
    out = np.full((count, channels), np.inf)
    for c in range(channels):
        if len(members[c]):
            out[:, c] = bounds[:, members[c]].min(axis=1)
    has_loose = np.array([bool((~exact[m]).any()) for m in members], dtype=bool)
    for n, c in np.argwhere((out < needed) & has_loose[None, :]):
        values = bounds[n, members[c]]
        loose = ~exact[members[c]]
        best = values[~loose].min(initial=np.inf)
        for k in np.argsort(values):
            if not loose[k]:
                continue
            if values[k] >= best and not everything:
                break
            values[k] = max(values[k], measure(n, members[c][k]))
            best = min(best, values[k])
        out[n, c] = values.min()
    return out


def _certified_pose(link: fcl.CollisionObject, shape: Shape, pose: np.ndarray,
                    obstacles: _Obstacles, p: int) -> float:
    """Tier 3: certified distance [m] between a posed link shape and obstacle p."""
    link.setTransform(fcl.Transform(pose[:3, :3], pose[:3, 3]))
    return _certified(link, shape, (pose[:3, :3], pose[:3, 3]), obstacles.fcl_objects()[p],
                      obstacles.shapes[p], (obstacles.rotations[p], obstacles.centres[p]))


def _pair_distance(a: Shape, a_pose: tuple[np.ndarray, np.ndarray], b: Shape,
                   b_pose: tuple[np.ndarray, np.ndarray]) -> float:
    """Certified distance [m] between two posed shapes (exact when one is a sphere)."""
    if a.kind == 'sphere' and b.kind in _EXACT_WITH_SPHERE:
        return float(signed_distance(b, b_pose[0].T @ (a_pose[1] - b_pose[1])) - a.radius)
    if b.kind == 'sphere' and a.kind in _EXACT_WITH_SPHERE:
        return float(signed_distance(a, a_pose[0].T @ (b_pose[1] - a_pose[1])) - b.radius)
    first = fcl.CollisionObject(fcl_geometry(a, _FCL_PADDING), fcl.Transform(*a_pose))
    second = fcl.CollisionObject(fcl_geometry(b, _FCL_PADDING), fcl.Transform(*b_pose))
    return _certified(first, a, a_pose, second, b, b_pose)


def _certified(first: fcl.CollisionObject, a: Shape, a_pose, second: fcl.CollisionObject,
               b: Shape, b_pose) -> float:
    """Lower bound [m] on the distance between two posed shapes from fcl's nearest points.

    0 when fcl finds contact (of the padded shapes): the penetration depth is never
    needed, only that the clearance is not positive. python-fcl gives the nearest points
    of some pairs (a mesh and a sphere) in each object's own frame rather than the
    world's, so both readings are tried: any direction gives a valid bound, the better
    one is kept.
    """
    request = fcl.DistanceRequest(enable_nearest_points=True,
                                  gjk_solver_type=fcl.GJKSolverType.GST_INDEP)
    result = fcl.DistanceResult()
    if fcl.distance(first, second, request, result) <= 0.0:
        return 0.0
    near_a, near_b = (np.asarray(p, dtype=float) for p in result.nearest_points)
    best = 0.0
    for direction in (near_b - near_a,
                      (b_pose[0] @ near_b + b_pose[1]) - (a_pose[0] @ near_a + a_pose[1])):
        norm = float(np.linalg.norm(direction))
        if norm > 0.0:
            best = max(best, separation(a, a_pose, b, b_pose, direction / norm))
    return best

"""Which cells of a joint grid a planar 3R arm among disks surely clears or surely hits.

The joint space is cut into N^3 closed cells. A cell's clearance channels (one per link:
the capsule's distance to the nearest disk, exact) change inside it by at most a bound,
so each cell is

* certified free when every channel at its centre exceeds the bound (every configuration
  in the closed cell is free), and
* possibly free unless some channel at its centre is below minus the bound (then every
  configuration in the cell collides).

For links 1 and 2 the bound is the better of the lever bound Σ_a R[k, a] · h_a (h the
half widths; `link_lever_arms`) and `link_box_clearance` (the disks turned back about the
joints before the link, the link's own turn exact). The last link is measured the second
way for every θ_3 cell of a (θ_1, θ_2) cell at once: per disk, the arc of directions in
which it may reach the disk from the wrist (`_classify`).

A joint-space triangle is checked with the same bounds, split where they do not decide
(`triangle_free`). Angles [rad], lengths [m]; the failure-tolerant set G is built on the
cells (tolerant_set.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from ..collision.distance_kernels import (
    ROUNDING,
    link_box_clearance,
    link_clearance_over_box,
    planar_joint_points,
    segment_gap2,
    sphere_drift,
)
from ..model.robot import PlanarChain
from ..model.scene import Scene

# [rad] every arc gives this much away to the rounding of arcsin and arccos near 1
_ANGLE_ROUNDING = 1e-6
# [m] a row of cells is passed over when the tool misses x by this much more than the
# reach at every angle of the last link: far beyond the rounding of the distances
_FAR_BEYOND_ROUNDING = 1e-9


def supports(scene: Scene) -> bool:
    """Whether the grid handles the scene: a planar 3R chain among spheres (disks)."""
    robot = scene.robot
    return (isinstance(robot, PlanarChain) and robot.n_joints == 3
            and all(ob.shape == 'sphere' for ob in scene.obstacles))


def disk_arrays(scene: Scene, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Return the scene's spheres as centres (P, 3) [m] and radii (P,) [m], grown by `margin`."""
    centres = np.array([ob.center for ob in scene.obstacles], dtype=float).reshape(-1, 3)
    radii = np.array([ob.radius for ob in scene.obstacles], dtype=float).reshape(-1) + margin
    return centres, radii


def link_lever_arms(lengths: np.ndarray) -> np.ndarray:
    """(n, n) R[k, a] = Σ_{m=a..k} ℓ_m [m]: how far any point of link k is from joint a.

    Turning joint a by δ moves every point of link k by at most R[k, a] |δ|.
    """
    n = len(lengths)
    arms = np.zeros((n, n))
    for k in range(n):
        for a in range(k + 1):
            arms[k, a] = lengths[a:k + 1].sum()
    return arms


@numba.njit(cache=True)
def _link_motion_bound(points, arms, half, k):
    """How far [m] a point of link k can move in a box of half widths `half` (n,) [rad].

    `points` (n+1, 2) are the joints at the box's centre; the bound is
    Σ_a h_a (d_ka + Σ_b R[k, b] h_b), plus `ROUNDING`.
    """
    stretch = 0.0
    for b in range(half.shape[0]):
        stretch += arms[k, b] * half[b]
    bound = ROUNDING
    for a in range(k + 1):
        d0 = np.sqrt((points[k, 0] - points[a, 0]) ** 2 + (points[k, 1] - points[a, 1]) ** 2)
        d1 = np.sqrt((points[k + 1, 0] - points[a, 0]) ** 2
                     + (points[k + 1, 1] - points[a, 1]) ** 2)
        bound += half[a] * (max(d0, d1) + stretch)
    return bound


@numba.njit(cache=True)
def _link_status(lengths, link_radius, centres, radii, arms, theta, half, k, points):
    """Status of link k over the cell of centre `theta` (n,) and half widths `half` (n,).

    0: every configuration of the cell collides; 1: every one is free; 2: unsure. Inside
    the cell a point of link k moves by at most Σ_a h_a (d_ka + Σ_b R[k, b] h_b), d_ka the
    farthest end of link k from joint a at the centre: the first term is its lever arm
    there, the second how much the cell can stretch it. Only joints 0..k count, so the
    status depends on the cell's extent in those joints alone. An unsure link is free
    still when `link_box_clearance` says so. `points` (n+1, 2) is scratch space.
    """
    planar_joint_points(lengths, theta, points)
    status = _segment_status(points[k], points[k + 1], centres, radii, link_radius,
                             _link_motion_bound(points, arms, half, k))
    if status == 2 and link_box_clearance(points, k, lengths[k], theta[:k + 1].sum(), half,
                                          centres, radii) > link_radius:
        return 1
    return status


@numba.njit(cache=True)
def _segment_status(a, b, centres, radii, link_radius, bound):
    """0 when the capsule a-b's clearance is below -bound, 1 when above bound, else 2.

    `segment_disk_clearance` compared on squared distances: no square roots.
    """
    status = 1
    for p in range(centres.shape[0]):
        gap2 = segment_gap2(a, b, centres[p])
        near = radii[p] + link_radius - bound
        if near > 0.0 and gap2 < near * near:
            return 0
        far = radii[p] + link_radius + bound
        if gap2 <= far * far:
            status = 2
    return status


@numba.njit(cache=True)
def _arc_half_width(distance, length, reach2):
    """Half width [rad] of the directions in which a segment hits a disk, or -1 for none.

    The segment runs `length` [m] from the origin; the disk's centre lies `distance` [m]
    away and its radius is sqrt(`reach2`) [m] (none when `reach2` < 0). The distance from
    the centre to the segment grows with the angle between the segment and the centre's
    direction (it is the distance to the line while the foot lies on the segment, then to
    the tip, then to the origin), so the directions within reach form one closed arc
    about the centre's direction: π when the origin lies in the disk.
    """
    if reach2 < 0.0:
        return -1.0
    reach = np.sqrt(reach2)
    if distance <= reach:
        return np.pi
    if distance > length + reach:
        return -1.0
    if distance <= length or reach2 >= distance * distance - length * length:
        return np.arcsin(reach / distance)  # the foot on the segment at the arc's end
    cosine = (distance * distance + length * length - reach2) / (2.0 * distance * length)
    return np.arccos(min(1.0, cosine))  # the tip at the arc's end


@numba.njit(cache=True)
def _mark_cells(counts, toward, width, base, step):
    """Count the cells k within `width` [rad] of the direction `toward` [rad], round the circle.

    Cell k's direction is base + (k + 1/2) · step [rad]; `counts` (N + 1,) holds the
    counts as differences (+1 at a run's first cell, -1 after its last).
    """
    cells = counts.shape[0] - 1
    if width >= np.pi:
        counts[0] += 1
        counts[cells] -= 1
        return
    turn = 2.0 * np.pi
    first = int(np.ceil((base + 0.5 * step - toward - width) / turn))
    last = int(np.floor((base + (cells - 0.5) * step - toward + width) / turn))
    for m in range(first, last + 1):
        centre = toward + m * turn
        low = max(0, int(np.ceil((centre - width - base) / step - 0.5)))
        high = min(cells - 1, int(np.floor((centre + width - base) / step - 0.5)))
        if low <= high:
            counts[low] += 1
            counts[high + 1] -= 1


# One piece, as a kernel: its three cell loops share the per-θ_1 and per-row scratch arrays.
@numba.njit(cache=True)
def _classify(lengths, link_radius, centres, radii, arms, lower, step, certified, possible):
    """Fill `certified` and `possible` (N, N, N) over the N^3 cells of the lattice.

    Links 1 and 2 get `_link_status` over the (θ_1) and (θ_1, θ_2) cells. For link 3, a
    turn x of joint 1 and y of joint 2 from the centre (a, b) moves the arm as turning the
    sphere back, by -x about the base and then by -y about the elbow p_1(a), would move the
    sphere: its centre c moves by at most |c| h_1 + (|c - p_1| + |c| h_1) h_2
    (`sphere_drift`).
    The wrist then stays where it is at the centre and only θ_3 turns the link, so per
    sphere and (θ_1, θ_2) cell the directions from the wrist within reach + drift
    (`_arc_half_width`), widened by h_3, mark the θ_3 cells that may collide, and those
    within reach - drift, narrowed by h_3, the ones that surely do. The drift depends on
    the base and the elbow only, so on the θ_1 cell: it is measured once per θ_1 cell.
    """
    cells = certified.shape[0]
    points = np.zeros((4, 2))
    theta = np.zeros(3)
    half = 0.5 * step
    may_hit = np.empty(cells + 1, dtype=np.int64)
    surely_hit = np.empty(cells + 1, dtype=np.int64)
    spheres = centres.shape[0]
    may_reach2 = np.empty(spheres)     # [m^2] the disk's radius squared, grown by the drift
    surely_reach2 = np.empty(spheres)  # [m^2] shrunk by it; NaN when the drift exceeds it
    beyond2 = np.empty(spheres)        # [m^2] a wrist farther than this misses the disk
    for i in range(cells):
        theta[0] = lower[0] + (i + 0.5) * step[0]
        first = _link_status(lengths, link_radius, centres, radii, arms, theta, half, 0, points)
        if first == 0:
            continue
        for p in range(spheres):  # points[0] and points[1], the base and elbow, are set
            drift = sphere_drift(points, 2, centres[p, 0], centres[p, 1], half) + ROUNDING
            reach = radii[p] + link_radius
            off_plane2 = centres[p, 2] * centres[p, 2]
            may_reach2[p] = (reach + drift) ** 2 - off_plane2
            surely_reach2[p] = (reach - drift) ** 2 - off_plane2 if reach > drift else np.nan
            # (_arc_half_width's `distance > length + reach`, with room for rounding)
            beyond2[p] = (lengths[2] + np.sqrt(may_reach2[p])) ** 2 * (1.0 + 1e-12) \
                if may_reach2[p] >= 0.0 else -1.0
        for j in range(cells):
            theta[1] = lower[1] + (j + 0.5) * step[1]
            second = _link_status(lengths, link_radius, centres, radii, arms, theta, half, 1,
                                  points)
            if second == 0:
                continue
            base = theta[0] + theta[1] + lower[2]
            may_hit[:] = 0
            surely_hit[:] = 0
            marked = False
            for p in range(spheres):
                dx, dy = centres[p, 0] - points[2, 0], centres[p, 1] - points[2, 1]
                distance2 = dx * dx + dy * dy
                if distance2 > beyond2[p]:
                    continue
                distance = np.sqrt(distance2)
                width = _arc_half_width(distance, lengths[2], may_reach2[p])
                if width < 0.0:
                    continue
                marked = True
                toward = np.arctan2(dy, dx)
                _mark_cells(may_hit, toward, width + half[2] + _ANGLE_ROUNDING, base, step[2])
                if np.isnan(surely_reach2[p]):
                    continue
                width = _arc_half_width(distance, lengths[2], surely_reach2[p])
                if width >= np.pi:
                    _mark_cells(surely_hit, toward, np.pi, base, step[2])
                elif width - half[2] - _ANGLE_ROUNDING >= 0.0:
                    _mark_cells(surely_hit, toward, width - half[2] - _ANGLE_ROUNDING, base,
                                step[2])
            free = first == 1 and second == 1
            if not marked:  # no disk within reach of link 3 anywhere in the row
                possible[i, j, :] = True
                certified[i, j, :] = free
                continue
            near, inside = 0, 0
            for k in range(cells):
                near += may_hit[k]
                inside += surely_hit[k]
                if inside == 0:
                    possible[i, j, k] = True
                    certified[i, j, k] = free and near == 0


@numba.njit(cache=True)
def triangle_free(lengths, link_radius, centres, radii, arms, corners, depth):
    """Whether every configuration of the triangle `corners` (3, n) [rad] is free.

    Over the box of the corners' spread about the centroid, every link must clear every
    disk by the lever bound of `_link_status` or by the fan bound of `link_box_clearance`
    (`link_clearance_over_box`); otherwise the triangle is split in four, `depth` times at
    most.
    """
    n = corners.shape[1]
    stack = np.empty((4 * depth + 1, 3, n))
    levels = np.empty(4 * depth + 1, dtype=np.int64)
    stack[0] = corners
    levels[0] = 0
    top = 1
    points = np.zeros((n + 1, 2))
    centre = np.empty(n)
    half = np.empty(n)
    while top > 0:
        top -= 1
        tri = stack[top].copy()
        level = levels[top]
        for a in range(n):
            centre[a] = (tri[0, a] + tri[1, a] + tri[2, a]) / 3.0
            half[a] = max(abs(tri[0, a] - centre[a]),
                          max(abs(tri[1, a] - centre[a]), abs(tri[2, a] - centre[a])))
        planar_joint_points(lengths, centre, points)
        free = True
        direction = 0.0
        for k in range(n):
            direction += centre[k]
            nearest, clear = link_clearance_over_box(
                points, k, lengths[k], direction, half,
                _link_motion_bound(points, arms, half, k), centres, radii, link_radius)
            if nearest - link_radius <= 0.0:
                return False
            free = free and clear
        if free:
            continue
        if level >= depth:
            return False
        ab = 0.5 * (tri[0] + tri[1])
        bc = 0.5 * (tri[1] + tri[2])
        ca = 0.5 * (tri[2] + tri[0])
        for piece in range(4):
            if piece == 0:
                stack[top, 0], stack[top, 1], stack[top, 2] = tri[0], ab, ca
            elif piece == 1:
                stack[top, 0], stack[top, 1], stack[top, 2] = ab, tri[1], bc
            elif piece == 2:
                stack[top, 0], stack[top, 1], stack[top, 2] = ca, bc, tri[2]
            else:
                stack[top, 0], stack[top, 1], stack[top, 2] = ab, bc, ca
            levels[top] = level + 1
            top += 1
    return True


@numba.njit(cache=True)
def _tool_near(lengths, lower, step, cells, x, reach, pool):
    """(N, N, N) bool: cells that may hold a configuration with the tool within `reach` [m] of x.

    With `pool` = 2, the (N/2)^3 blocks of 2^3 cells that hold such a cell (N even).

    In a cell the wrist moves by at most (ℓ_1 + ℓ_2) h_1 + ℓ_2 h_2 from where it is at
    the centre (h the half widths) and the last link's direction φ = θ_1 + θ_2 + θ_3
    turns by at most h_1 + h_2 + h_3. So the tool may come within `reach` of x only if,
    from the centre's wrist w, the last link at some direction of that range ends within
    `reach` plus the wrist's motion of x: |w + ℓ_3 u(φ) - x| <= r holds for the
    directions φ within an arc about the direction of x - w (the law of cosines), which
    marks the θ_3 cells of the row as `_classify` marks those within reach of a disk.
    """
    blocks = cells // pool
    out = np.zeros((blocks, blocks, blocks), dtype=np.bool_)
    half = 0.5 * step
    r = reach + (lengths[0] + lengths[1]) * half[0] + lengths[1] * half[1]
    turn = half[0] + half[1] + half[2] + _ANGLE_ROUNDING
    last = lengths[2]
    marks = np.empty(cells + 1, dtype=np.int64)
    for i in range(cells):
        a = lower[0] + (i + 0.5) * step[0]
        elbow_x, elbow_y = lengths[0] * np.cos(a), lengths[0] * np.sin(a)
        for j in range(cells):
            b = a + lower[1] + (j + 0.5) * step[1]
            qx = x[0] - elbow_x - lengths[1] * np.cos(b)  # from the wrist to x
            qy = x[1] - elbow_y - lengths[1] * np.sin(b)
            distance = np.sqrt(qx * qx + qy * qy)
            if abs(distance - last) > r + _FAR_BEYOND_ROUNDING:
                continue  # the wrist is too near or too far for the last link to reach
            if distance + last <= r or distance == 0.0:
                width = np.pi  # every direction reaches (or x sits on the wrist)
            else:
                cosine = (last * last + distance * distance - r * r) / (2.0 * last * distance)
                width = np.arccos(min(1.0, max(-1.0, cosine)))
            marks[:] = 0
            _mark_cells(marks, np.arctan2(qy, qx), width + turn, b + lower[2], step[2])
            inside = 0
            for k in range(cells):
                inside += marks[k]
                if inside > 0:
                    out[i // pool, j // pool, k // pool] = True
    return out


def _pooled_cells(cells: int) -> int:
    """Return N/2, the blocks per joint of N cells pooled in pairs; ValueError for N odd."""
    if cells % 2:
        raise ValueError(f'{cells} cells per joint cannot be pooled in pairs')
    return cells // 2


def pool_blocks(mask: np.ndarray, every: bool) -> np.ndarray:
    """Pool a mask (N, N, N) bool (N even) into blocks of 2^3: (N/2)^3, all of a block or any."""
    out = np.empty((_pooled_cells(mask.shape[0]),) * 3, dtype=np.bool_)
    _pool(np.ascontiguousarray(mask, dtype=np.bool_), every, out)
    return out


@numba.njit(cache=True)
def _pool(mask, every, out):
    """Fill `out` (N/2)^3 from `mask` (N)^3: all of each block's 2^3 cells, or any."""
    half = out.shape[0]
    for i in range(half):
        for j in range(half):
            for k in range(half):
                value = every
                for a in range(2 * i, 2 * i + 2):
                    for b in range(2 * j, 2 * j + 2):
                        if every:
                            value &= mask[a, b, 2 * k] & mask[a, b, 2 * k + 1]
                        else:
                            value |= mask[a, b, 2 * k] | mask[a, b, 2 * k + 1]
                out[i, j, k] = value


@dataclass(frozen=True)
class JointLattice:
    """N cells per joint over the joint ranges: `lower` (3,) [rad], `step` (3,) [rad]."""

    cells: int
    lower: np.ndarray
    step: np.ndarray
    periodic: np.ndarray

    @classmethod
    def over(cls, robot: PlanarChain, cells: int) -> JointLattice:
        """Cover every joint's range (its limits, or (-π, π]) with `cells` cells."""
        limits = robot.limits
        return cls(cells, limits[:, 0].copy(), (limits[:, 1] - limits[:, 0]) / cells,
                   robot.periodic.copy())

    def centres(self, index: np.ndarray, size: int = 1) -> np.ndarray:
        """Centres (c, 3) [rad] of cells `index` (c, 3) of `size` fine cells per edge."""
        return self.lower + (index + 0.5) * size * self.step

    def cell_of(self, thetas: np.ndarray) -> np.ndarray:
        """Index (c, 3) of a closed cell holding each configuration (c, 3) [rad]."""
        offset = np.floor((np.asarray(thetas) - self.lower) / self.step).astype(np.int64)
        wrapped = np.mod(offset, self.cells)
        return np.where(self.periodic, wrapped, np.clip(offset, 0, self.cells - 1))

    def tool_near(self, robot: PlanarChain, x: np.ndarray, tolerance: float = 0.0,
                  pooled: bool = False) -> np.ndarray:
        """(N, N, N) bool: cells that may hold a configuration with the tool within tolerance of x.

        Each cell's wrist and last link are bounded apart (`_tool_near`). `pooled`: the
        (N/2)^3 blocks of 2^3 cells that hold such a cell, as `pool_blocks` would pool
        the mask, without the mask (N even).
        """
        if pooled:
            _pooled_cells(self.cells)  # raises for an odd N
        return _tool_near(np.asarray(robot.link_lengths, dtype=float), self.lower, self.step,
                          self.cells, np.asarray(x, dtype=float)[:2], tolerance + ROUNDING,
                          2 if pooled else 1)

    def inside(self, thetas: np.ndarray) -> np.ndarray:
        """(c,) bool: configurations within the limits of the joints that have them."""
        upper = self.lower + self.cells * self.step
        within = (thetas >= self.lower) & (thetas <= upper)
        return np.all(within | self.periodic, axis=1)


@dataclass(frozen=True, eq=False)
class CellClasses:
    """Every cell certified free, possibly free, or neither (then surely colliding)."""

    lattice: JointLattice
    certified: np.ndarray   # (N, N, N) bool
    possible: np.ndarray    # (N, N, N) bool

    def pooled(self) -> CellClasses:
        """Return the classes of the grid of N/2 cells per joint, each a block of 2^3 (N even).

        A block is certified free when its eight cells are and possibly free when one is:
        as sound as the classes it pools and, with bounds from cells of half the width,
        often sharper than classifying the coarse grid itself.
        """
        cells = self.lattice.cells
        certified = pool_blocks(self.certified, every=True)
        possible = pool_blocks(self.possible, every=False)
        lattice = JointLattice(cells // 2, self.lattice.lower.copy(), 2.0 * self.lattice.step,
                               self.lattice.periodic.copy())
        return CellClasses(lattice, certified, possible)


def classify_cells(scene: Scene, cells: int, margin: float = 0.0) -> CellClasses:
    """Classify the N^3 cells (`_classify`); free means clear by more than `margin` [m].

    The disks grow by the margin.
    """
    if cells < 1:
        raise ValueError(f'cells ({cells}) must be at least 1')
    robot = scene.robot
    lattice = JointLattice.over(robot, cells)
    lengths = np.asarray(robot.link_lengths, dtype=float)
    centres, radii = disk_arrays(scene, margin)
    certified = np.zeros((cells,) * 3, dtype=bool)
    possible = np.zeros((cells,) * 3, dtype=bool)
    _classify(lengths, float(robot.link_radius), centres, radii, link_lever_arms(lengths),
              lattice.lower, lattice.step, certified, possible)
    return CellClasses(lattice, certified, possible)

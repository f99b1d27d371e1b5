"""Which pairs of links to check for self-collision, as MoveIt's setup assistant chooses.

Pairs that always touch (adjacent links, housings that overlap whatever the joints do)
would make every configuration collide, and pairs that never touch cost time: MoveIt's
setup assistant exempts both, and so does a robot here that comes without a list of its
own (an SRDF or `disabled_collisions`). `sample_collisions` counts, over random
configurations uniform within the joint limits, how often each pair of links touches;
`choose_exceptions` then exempts

- 'adjacent' pairs: links joined by a joint, or by a chain of links without geometry;
- 'always': pairs touching in at least ALWAYS_FRACTION (95 %) of the samples;
- 'never': pairs touching in none of them.

SAMPLES is MoveIt's default sampling density, 10,000 configurations. Exempting 'never'
pairs is a modelling choice, MoveIt's: a pair that touches only in a small corner of the
joint space that the samples missed goes unchecked (`never=False` keeps them checked). MoveIt
also exempts pairs touching in the robot's default configuration; this module does not
(a pair touching there but apart in most samples stays checked).

Touching is decided exactly, up to fcl: bounding spheres rule out shapes far apart, and
fcl's collide decides the rest (capsules thinner than 1 cm count as 1 cm thick, as in the
checker; a mesh is its triangles, so one wholly inside another is not seen touching).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import pairwise

import fcl
import numpy as np

from ..model.chain import ChainModel
from ..model.geometry import fcl_geometry
from ..model.robot import Robot
from ..model.spatial import SpatialArm

SAMPLES = 10_000  # MoveIt setup assistant's default sampling density
ALWAYS_FRACTION = 0.95  # a pair touching in this share of the samples counts as always
_FCL_PADDING = 1e-2  # [m] thinnest capsule or sphere handed to fcl (as the checker's)
_CHUNK = 1000  # configurations posed at once


@dataclass(frozen=True)
class Sampling:
    """How a robot's exceptions are sampled (see the module docstring).

    `samples` configurations drawn by a generator seeded with `seed`; `never` exempts the
    pairs touching in none of them, as MoveIt does.
    """

    samples: int = SAMPLES
    never: bool = True
    seed: int = 0


def sample_collisions(model: ChainModel, samples: int, rng: np.random.Generator,
                      ) -> dict[tuple[int, int], int]:
    """Count, per pair of links (a, b) with geometry and not adjacent, the samples they touch in.

    `samples` configurations uniform within the joint limits ((-π, π] for continuous
    joints), drawn from `rng`.
    """
    arm = SpatialArm(model)
    thetas = rng.uniform(arm.limits[:, 0], arm.limits[:, 1], size=(samples, model.n_joints))
    contacts = Contacts(arm, sampled_pairs(model))
    touching = np.zeros(len(contacts.pairs), dtype=np.int64)
    for start in range(0, samples, _CHUNK):
        touching += contacts.touching(thetas[start:start + _CHUNK]).sum(axis=0)
    return {pair: int(count) for pair, count in zip(contacts.pairs, touching, strict=True)}


def pair_contacts(model: ChainModel, thetas: np.ndarray,
                  ) -> tuple[list[tuple[int, int]], np.ndarray]:
    """Return the pairs `sampled_pairs` names and whether each touches (N, pairs) at θ (N, n)."""
    contacts = Contacts(SpatialArm(model), sampled_pairs(model))
    return contacts.pairs, contacts.touching(np.atleast_2d(np.asarray(thetas, dtype=float)))


def choose_exceptions(model: ChainModel, counts: Mapping[tuple[int, int], int], samples: int,
                      never: bool = True) -> dict[tuple[int, int], str]:
    """Return the pairs to exempt with why: 'adjacent', 'always' or 'never' (module docstring).

    `counts` are `sample_collisions`' over `samples` configurations; `never=False` keeps
    the pairs that never touched checked.
    """
    out = {pair: 'adjacent' for pair in adjacent_pairs(model)}
    for pair, count in counts.items():
        if count >= ALWAYS_FRACTION * samples:
            out[pair] = 'always'
        elif count == 0 and never:
            out[pair] = 'never'
    return dict(sorted(out.items()))


def sample_disabled_pairs(model: ChainModel, samples: int, rng: np.random.Generator,
                          never: bool = True) -> dict[tuple[int, int], str]:
    """Sample, then choose the pairs to exempt, with why (`choose_exceptions`)."""
    return choose_exceptions(model, sample_collisions(model, samples, rng), samples, never)


def sampled_pairs(model: ChainModel) -> list[tuple[int, int]]:
    """Return the pairs of links (a, b), a < b, that `sample_collisions` counts."""
    links = sorted({item.link for item in model.shapes})
    adjacent = adjacent_pairs(model)
    return [(a, b) for k, a in enumerate(links) for b in links[k + 1:] if (a, b) not in adjacent]


def adjacent_pairs(model: ChainModel) -> frozenset[tuple[int, int]]:
    """Pairs of links with geometry that only links without geometry separate along the chain.

    That is links joined by a joint, and, as MoveIt counts them, links joined through
    links that have no geometry (a link between them with nothing to collide with).
    """
    links = sorted({item.link for item in model.shapes})
    return frozenset(pairwise(links))


class Contacts:
    """Whether pairs of a robot's links touch: bounding spheres, then fcl's collide.

    `pairs` are link pairs (a, b); each is tested shape by shape (module docstring).
    """

    def __init__(self, robot: Robot, pairs: Sequence[tuple[int, int]]):
        self.robot = robot
        self.pairs = list(pairs)
        self.shapes = robot.collision_shapes
        self.links = np.array([item.link for item in self.shapes], dtype=np.int64)
        self.placements = np.array([item.placement for item in self.shapes]).reshape(-1, 4, 4)
        spheres = [item.shape.bounding_sphere() for item in self.shapes]
        self.centres = np.array([centre for centre, _ in spheres]).reshape(-1, 3)
        self.radii = np.array([radius for _, radius in spheres])
        self.objects = [fcl.CollisionObject(fcl_geometry(item.shape, _FCL_PADDING))
                        for item in self.shapes]
        # Shape pairs (s, t) and the link pair k each belongs to.
        rows = [(s, t, k) for k, (a, b) in enumerate(self.pairs)
                for s in np.flatnonzero(self.links == a) for t in np.flatnonzero(self.links == b)]
        self.shape_pairs = np.array(rows, dtype=np.int64).reshape(-1, 3)

    def touching(self, thetas: np.ndarray) -> np.ndarray:
        """(N, pairs) bool: whether each link pair touches at configurations (N, n) [rad]."""
        return self._test(thetas, by_shape=False)

    def shapes_touching(self, thetas: np.ndarray) -> np.ndarray:
        """(N, Q) bool: whether each shape pair (`shape_pairs`) touches at (N, n) [rad]."""
        return self._test(thetas, by_shape=True)

    def _test(self, thetas: np.ndarray, by_shape: bool) -> np.ndarray:
        """Test shape pairs near enough to touch; a link pair's stop at its first contact."""
        s, t, k = self.shape_pairs.T
        out = np.zeros((len(thetas), len(s) if by_shape else len(self.pairs)), dtype=bool)
        if not len(s):
            return out
        frames = self.robot.link_frames(thetas)  # (N, L, 4, 4)
        poses = np.einsum('nsij,sjk->nsik', frames[:, self.links], self.placements)
        centres = np.einsum('nsij,sj->nsi', poses[:, :, :3, :3], self.centres) + poses[:, :, :3, 3]
        near = (np.linalg.norm(centres[:, s] - centres[:, t], axis=2)
                <= self.radii[s] + self.radii[t])
        request = fcl.CollisionRequest()
        for n, q in zip(*np.nonzero(near), strict=True):
            column = q if by_shape else k[q]
            if out[n, column]:
                continue
            first, second = self.objects[s[q]], self.objects[t[q]]
            first.setTransform(fcl.Transform(poses[n, s[q], :3, :3], poses[n, s[q], :3, 3]))
            second.setTransform(fcl.Transform(poses[n, t[q], :3, :3], poses[n, t[q], :3, 3]))
            out[n, column] = fcl.collide(first, second, request, fcl.CollisionResult()) > 0
        return out

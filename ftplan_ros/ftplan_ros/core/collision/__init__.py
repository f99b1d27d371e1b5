"""Clearances of the arm and certificates that pieces of joint space are free.

`checker.CollisionChecker` measures, in batches, each link against the obstacles and
pairs of links apart (tiers of bounds, then exact distances: `distance_kernels`, fcl);
`self_collision` chooses the pairs of links that are checked at all; `blocking` says which
obstacle or pair of links blocks a manifold with no free point. `certification`
turns clearances into proofs over the continuum: segments, triangles and whole webs of
joint paths are free when every clearance beats how far it can change inside them. The
paper's steps (`core.paper`) and the grids (`core.grid`) build on these.
"""

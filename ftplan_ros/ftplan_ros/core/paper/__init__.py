"""The paper's method (Jamisola, Maciejewski, Roberts, IROS 2003), step by step.

Steps 1-2, self-motion manifolds and their obstacle-free parts: `manifolds` (traced by
the compiled predictor-corrector of `continuation`). Steps 3-4, failure hyperplanes, the
necessary condition (eq. 6) and the failure hypercube: `failure_planes`. Steps 5-6, the
failure surface S_F as a web of joint paths: `failure_surface`. Step 7, the recovery
from a lock, walked on S_F's slice: `recovery`. The self-check that every plan passes
before it is called failure-tolerant: `verification` (with `slices` for part 3 and
`core.collision.certification` for part 1). `result` and `options` are the planner's
answer and settings. The search over these steps lives in `core.planning`.
"""

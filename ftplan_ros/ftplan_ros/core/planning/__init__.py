"""Planning entry points: the search over the paper's steps, approaches and drills.

`planner.plan` checks a scene and runs the paper's search for its degree of redundancy:
`surface_search` for r = 1 (Steps 1-6 and the self-check), `curves` for r >= 2 (a curve
on each manifold, then as for r = 1), then the recovery sheets of `core.grid` where the
paper's surface is not enough. `approach` plans for an arm standing elsewhere (θ_s
reached along M_s or by a certified joint move, or a proof that none is reachable);
`drill` locks random joints on a plan and checks the arm still arrives; `warmup` loads
the compiled kernels before the first plan.
"""

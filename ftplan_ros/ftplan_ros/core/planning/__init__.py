"""Planning entry points: the search over the paper's steps, approaches and drills.

`planner.plan` checks a scene and runs the paper's search for its degree of redundancy:
`surface_search` for r = 1 (Steps 1-6 and the self-check), `curves` for r >= 2 (a curve
on each manifold, then as for r = 1), then the recovery sheets of `core.grid` where the
paper's surface is not enough. `approach` plans the ordinary motions of an arm standing
elsewhere (to θ_s along M_s or by a certified joint move); `reachable.plan_from` plans
for it: a plan with a certified approach, none reachable (proved), or none found within
the search; `drill` locks random joints on a plan and checks the arm still arrives; `warmup` loads
the compiled kernels before the first plan.
"""

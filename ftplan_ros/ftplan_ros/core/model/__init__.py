"""The robot and its world as data: kinematics, task spaces, geometry, scenes.

Robots behind one interface (`robot.Robot`: the paper's f(θ) and its task-error map):
planar chains (`robot.PlanarChain`) and spatial chains (`chain.ChainModel` from `urdf`
or `dh`, bound to a task kind by `spatial.SpatialArm`), with the compiled task maps in
`kinematics`. `task_space` says what a task point is (planar, position, axis, pose);
`geometry` the convex shapes of links and obstacles; `scene` the obstacles, the task and
the scene that holds them. `angles` and `paths` are joint-space helpers (wrapping on the
torus, polylines by fraction of length). Nothing here knows about collisions or plans.
"""

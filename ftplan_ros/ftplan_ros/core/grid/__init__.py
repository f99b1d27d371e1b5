"""Joint grids of planar 3R arms among disks: existence, proofs, and the recovery sheets.

Cells of an N^3 grid are certified free, possibly free or surely colliding
(`cell_classes`), joined into components round the periodic joints (`components`). On
them `tolerant_set` bounds the failure-tolerant set G from both sides, `existence`
decides whether any failure-tolerant plan exists (YES, NO or UNSURE),
`free_components` proves that no collision-free joint move joins two configurations (or
joins them through certified cells), and `start_reach` finds the failure-tolerant starts
within the reach of an arm standing somewhere, or proves there are none.
The recovery-sheets planner (`recovery_sheets`, with `sheet_builder` and the compiled
`sheet_kernels`) plans past the paper's surface through G. `exhaustive` holds the
brute-force baselines the planner is checked and timed against.
"""

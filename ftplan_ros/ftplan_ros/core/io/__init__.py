"""Files a user gives, read and validated: scenes, robot configs, URDFs, fingerprints.

`files` reads text and YAML with bounds and the traps of YAML closed; `scene_file` turns
a scene YAML (CONTRACT.md) into `core.model` objects, naming the field of every bad
value in an `InputError`; `mesh_files` finds a URDF's meshes as ROS does (package://,
file://, paths); `sampled_exceptions` gives a robot without its own self-collision
exceptions MoveIt's sampled ones, kept in `cache` (ftplan's cache folder, outside the
repository); `fingerprint` writes scenes back as plain data and names them by a digest,
for caches and studies. Nothing below this package reads a file.
"""

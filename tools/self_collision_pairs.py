"""Write the self-collision exceptions of a robot config, as MoveIt's setup assistant does.

Samples random configurations within the joint limits and exempts the link pairs that
are adjacent, that touch in at least 95 % of the samples, or that never touch; the rest
are checked by the planner. The list goes into the robot YAML as `disabled_collisions`,
each pair with its reason, replacing any list there.

    .venv/bin/python tools/self_collision_pairs.py config/robots/panda.yaml [--samples 20000]
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from ftplan_ros.core.collision.self_collision import sample_disabled_pairs
from ftplan_ros.core.io.scene_file import parse_scene

_MARK = 'disabled_collisions:'


def main() -> None:
    """Analyse the robot of a robot YAML and rewrite its list of exempted link pairs."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('robot', type=Path, help='robot YAML (robot: {type: urdf, ...})')
    parser.add_argument('--samples', type=int, default=20_000)
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args()
    scene = parse_scene({'robot': args.robot.name}, directory=args.robot.parent)
    model = replace(scene.robot.model, disabled_pairs=frozenset())
    pairs = sample_disabled_pairs(model, args.samples, np.random.default_rng(args.seed))
    names = model.link_names
    lines = [f'  {_MARK}  # {len(pairs)} pairs: tools/self_collision_pairs.py, '
             f'{args.samples} samples, seed {args.seed}']
    lines += [f'    - [{names[a]}, {names[b]}]  # {why}' for (a, b), why in sorted(pairs.items())]
    text = args.robot.read_text()
    kept = text.split(f'  {_MARK}')[0].rstrip('\n')
    args.robot.write_text(kept + '\n' + '\n'.join(lines) + '\n')
    checked = len(model.self_collision_pairs) - len(pairs)
    print(f'{args.robot}: {len(pairs)} pairs exempted, {checked} checked')


if __name__ == '__main__':
    main()

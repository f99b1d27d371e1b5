"""Studies: thousands of plans over a map of positions or a random sweep, on Dask.

    study = load_study('config/studies/paper_map.yaml')    # validated spec (spec.py)
    store = ResultStore('out/paper_map', study)             # Parquet per chunk (results.py)
    with open_client(None, 2) as client:                    # LocalCluster of 2 workers
        run_study(study, store, client)                     # resumable (runner.py)
    print(summarize(study, store.read()))                   # summary.py; figures.py draws

Workers run `tasks.run_chunk`: each task is planned as `ftplan plan` would plan it.
Nothing here imports rclpy; Dask and pyarrow load only when this package does.
"""

from .command import draw_study, open_client, run_study_command
from .results import OUTCOMES, ResultStore, result_schema
from .runner import StudyError, StudyRun, run_study
from .spec import Study, StudyTask, load_study, parse_study
from .summary import feasible_rate_by, summarize, wilson_interval
from .tasks import plan_study_task, run_chunk

__all__ = [
    'OUTCOMES', 'ResultStore', 'Study', 'StudyError', 'StudyRun', 'StudyTask', 'draw_study',
    'feasible_rate_by', 'load_study', 'open_client', 'parse_study', 'plan_study_task',
    'result_schema', 'run_chunk', 'run_study', 'run_study_command', 'summarize',
    'wilson_interval',
]

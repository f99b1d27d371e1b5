"""ftplan's cache folder: results worth keeping between runs, kept outside any repository.

The folder is `$FTPLAN_CACHE_DIR` when set, else `$XDG_CACHE_HOME/ftplan`, else
`~/.cache/ftplan`. An entry is a JSON file `<kind>/<key>.json`, written whole: into a
temporary file beside it, then renamed over it. So writers racing on one entry leave one
complete copy, and a reader sees the old entry or the new one, never half of one. The
cache only saves time: an entry that cannot be read is treated as missing, and a folder
that cannot be written costs the entry, never the result (both are logged).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import re
import tempfile
from pathlib import Path
from typing import Any

log = logging.getLogger(__name__)

LARGEST_ENTRY = 10 * 1024 * 1024  # [bytes] an entry read back; larger ones are ignored
_NAME = re.compile(r'[A-Za-z0-9_.-]+')


def cache_dir() -> Path:
    """Return the cache folder (see the module docstring); it may not exist yet."""
    if os.environ.get('FTPLAN_CACHE_DIR'):
        return Path(os.environ['FTPLAN_CACHE_DIR'])
    base = os.environ.get('XDG_CACHE_HOME') or str(Path.home() / '.cache')
    return Path(base) / 'ftplan'


def entry_path(kind: str, key: str) -> Path:
    """Return where the entry `key` of `kind` lives (names of letters, digits, '_.-')."""
    for name in (kind, key):
        if not _NAME.fullmatch(name) or name.startswith('.'):
            raise ValueError(f'cache names are letters, digits, "_", "." and "-": got {name!r}')
    return cache_dir() / kind / f'{key}.json'


def read_entry(kind: str, key: str) -> Any | None:
    """Return the entry's data, or None when it is missing or cannot be read."""
    path = entry_path(kind, key)
    try:
        if path.stat().st_size > LARGEST_ENTRY:
            raise ValueError(f'larger than {LARGEST_ENTRY} bytes')
        return json.loads(path.read_text(encoding='utf-8'))
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as error:
        log.warning('ignoring the cache entry %s: %s', path, error)
        return None


def write_entry(kind: str, key: str, data: Any) -> Path | None:
    """Write the entry (JSON) whole; return its path, or None when it could not be written."""
    path = entry_path(kind, key)
    temporary = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        descriptor, temporary = tempfile.mkstemp(dir=path.parent, prefix=f'.{key}.',
                                                 suffix='.tmp')
        with os.fdopen(descriptor, 'w', encoding='utf-8') as file:
            json.dump(data, file)
        os.replace(temporary, path)
        return path
    except OSError as error:
        log.warning('could not write the cache entry %s (%s): it will be computed again next '
                    'time; set FTPLAN_CACHE_DIR to a writable folder', path, error)
        if temporary is not None:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
        return None

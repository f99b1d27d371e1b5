"""Reading robot descriptions (URDF, SRDF) as XML: bounded, hardened, numbers checked.

A description arrives as text, from a file or from a topic anyone may publish on, and
goes on to C++ parsers (Pinocchio's, through urdfdom and TinyXML) that trust it. So it
is read by expat first, with limits that no real robot comes near: the size in bytes,
the number of elements and their nesting depth. A document with a DOCTYPE is refused:
no entity is ever declared, so none can expand (the "billion laughs") or be fetched,
and TinyXML, which expands none, reads the same text as we do. Errors are InputError
naming `where`, the field the text came from.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ElementTree
from xml.parsers import expat

from ..errors import InputError
from ..validation import LARGEST_NUMBER

MAX_DEPTH = 32  # nesting of elements: a URDF's deepest (robot/link/collision/geometry/box) is 5
MAX_ELEMENTS = 100_000  # elements of any tag, ROS control and Gazebo tags too

# A decimal number as urdfdom reads one: no inf, nan, hex or digit separators.
_NUMBER = re.compile(r'[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?')


class _Refused(Exception):  # noqa: N818 - stops expat from a handler; becomes InputError
    """Raised by a handler to stop the parse, with the problem."""


def parse_description(text: str, where: str, max_bytes: int) -> ElementTree.Element:
    """Parse a description's text into elements; InputError `where` for anything else.

    Refuses text over `max_bytes` (UTF-8), more than MAX_ELEMENTS elements, a nesting
    deeper than MAX_DEPTH, a DOCTYPE, and XML that is not well formed.
    """
    if not isinstance(text, str):
        raise InputError(where, f'must be XML text, got {type(text).__name__}')
    try:
        data = text.encode('utf-8') if len(text) <= max_bytes else None
    except UnicodeEncodeError:
        raise InputError(where, 'is not UTF-8 text') from None
    if data is None or len(data) > max_bytes:
        size = len(text) if data is None else len(data)  # characters: at least as many bytes
        raise InputError(where, f'has {"at least " if data is None else ""}{size} bytes, more '
                         f'than the {max_bytes} a robot description may have')
    builder = ElementTree.TreeBuilder()
    parser = expat.ParserCreate()
    counts = {'elements': 0, 'depth': 0}

    def start(tag: str, attributes: dict) -> None:
        counts['elements'] += 1
        counts['depth'] += 1
        if counts['elements'] > MAX_ELEMENTS:
            raise _Refused(f'has more than {MAX_ELEMENTS} XML elements')
        if counts['depth'] > MAX_DEPTH:
            raise _Refused(f'nests <{tag}> deeper than {MAX_DEPTH} elements (line '
                           f'{parser.CurrentLineNumber})')
        builder.start(tag, attributes)

    def end(tag: str) -> None:
        counts['depth'] -= 1
        builder.end(tag)

    def doctype(*_) -> None:
        raise _Refused('has a DOCTYPE: a robot description needs none (its entities would '
                       'be read differently by Pinocchio\'s parser); remove it')

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = builder.data
    parser.StartDoctypeDeclHandler = doctype
    parser.EntityDeclHandler = doctype
    try:
        parser.Parse(data, True)
    except _Refused as refused:
        raise InputError(where, str(refused)) from None
    except expat.ExpatError as error:
        raise InputError(where, f'is not valid XML ({error})') from None
    return builder.close()


def serialize(root: ElementTree.Element) -> str:
    """Return the elements as XML text: what the C++ parsers read, as it was checked."""
    return ElementTree.tostring(root, encoding='unicode')


def read_numbers(element: ElementTree.Element, attribute: str, count: int, where: str,
                 what: str, default: str | None = None) -> list[float]:
    """Read `count` numbers from an attribute, each finite and within ±LARGEST_NUMBER.

    `what` says whose attribute it is in errors (e.g. "joint 'j' <origin>"); a missing
    attribute takes `default`, or is an error without one.
    """
    text = element.get(attribute, default)
    if text is None:
        raise InputError(where, f'{what} has no {attribute}=: give {count} number'
                         f'{"s" if count > 1 else ""}')
    items = text.split()
    if len(items) != count:
        raise InputError(where, f'{what} {attribute}="{text:.60}" needs {count} number'
                         f'{"s" if count > 1 else ""}, got {len(items)}')
    values = []
    for item in items:
        if not _NUMBER.fullmatch(item):
            raise InputError(where, f'{what} {attribute}="{text:.60}": {item!r:.30} is not a '
                             'decimal number')
        value = float(item)
        if not (math.isfinite(value) and abs(value) <= LARGEST_NUMBER):
            raise InputError(where, f'{what} {attribute}="{text:.60}": {item:.30} is not '
                             f'within ±{LARGEST_NUMBER:g}, the bound of every number ftplan '
                             'reads: write a value within it, or leave the element out')
        values.append(value)
    return values

"""The generated sections of the docs: the lines between two marker lines of a page, written from the code
(the table of artifact kinds in docs/extending.md, :mod:`magexp.artifacts.kinds`; the table of recording
formats in docs/calibrate.md, :mod:`magexp.core.readers`), so a test can hold each page current.
"""

from __future__ import annotations

from magexp.errors import MagexpError


def with_section(text: str, begin: str, end: str, section: str) -> str:
    """``text`` with the lines from marker ``begin`` to marker ``end`` replaced by ``section`` (which holds both);
    one line if the page does not hold each marker once.
    """
    if text.count(begin) != 1 or text.count(end) != 1:
        raise MagexpError(f"the page must hold the lines {begin!r} and {end!r} once each")
    head, rest = text.split(begin)
    return head + section + rest.split(end, 1)[1]

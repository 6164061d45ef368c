"""Keywords of the API's front doors, checked where they enter.

``optimize`` and ``mpc`` take a few keywords beside their settings; one they do not take is
refused there, naming the allowed ones, and a keyword of an earlier release says what it became,
instead of a ``TypeError`` from deep inside.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

# Keywords of earlier releases and what took their place.
RENAMED = {"method": "solver"}


def refuse_unknown(
    where: str,
    given: Mapping[str, object],
    allowed: Iterable[str],
    renamed: Mapping[str, str] = RENAMED,
) -> None:
    """Refuse the keywords in ``given`` (TypeError naming them and the ``allowed`` ones).

    Parameters
    ----------
    where : str
        The function, as the message names it (``"optimize"``).
    given : mapping
        The keywords it took beyond its own.
    allowed : iterable of str
        Every keyword it takes.
    renamed : mapping
        Old keywords and the new ones that replaced them.
    """
    if not given:
        return
    name = next(iter(given))
    if name in renamed:
        raise TypeError(
            f"{where}({name}={given[name]!r:.40}): the keyword {name!r} is now "
            f"{renamed[name]!r} ({where}(..., {renamed[name]}={given[name]!r:.40}))"
        )
    raise TypeError(f"{where}: unknown keyword {name!r}; allowed: {', '.join(sorted(allowed))}")

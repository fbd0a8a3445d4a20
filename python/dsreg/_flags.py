"""Keyword options as command-line flags.

The keyword options of dsreg.regularize (and of read_volume, digitize and evaluate) are the
flags of ``dsreg regularize`` (``dsreg eval``), read from the command line's own definitions in
the C++ module: ``--ii-kernel`` is ``ii_kernel=``. A keyword's value is written as the flag's text
(``ii_kernel="ball"`` → ``--ii-kernel=ball``, ``raw_dims=(4, 5, 6)`` → ``--raw-dims=4,5,6``,
``clamp=True`` → ``--clamp``) and parsed by the same parser as on the command line, so that a flag
added to the command line is a keyword option at once, with the same checks and messages.
"""

import difflib
import numbers
import os
import textwrap
from typing import Dict, List, Mapping, NamedTuple, Optional

import numpy as np


class Flag(NamedTuple):
    """A flag of the command line."""

    name: str  #: without the leading "--", e.g. "ii-kernel"
    values: int  #: values it takes: 0 for a switch (--clamp), 3 for --raw-dims X,Y,Z, -1 for a list (--labels 1,4,7)
    type: str  #: as --help shows it, e.g. "FLOAT", "TEXT:{ball,biweight}"
    default: str  #: as --help shows it ("" if none)
    help: str

    @property
    def keyword(self) -> str:
        return self.name.replace("-", "_")


def flag_table(raw) -> Dict[str, Flag]:
    """The C++ module's flag list as {keyword: Flag}, in the order of --help."""
    return {flag.keyword: flag for flag in (Flag(*entry) for entry in raw)}


def _value_text(keyword: str, value) -> str:
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{keyword}= takes a value, not {value!r}")
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))  # shortest text that reads back to the same double
    if isinstance(value, (str, os.PathLike)):
        return os.fspath(value)
    raise TypeError(f"{keyword}= takes a number or a string (got {type(value).__name__})")


def _flag_argument(flag: Flag, value) -> Optional[str]:
    """The command-line argument of `flag` set to `value`, or None for a switch set to False."""
    if flag.values == 0:
        if not isinstance(value, (bool, np.bool_)):
            raise TypeError(f"{flag.keyword}= takes True or False (got {value!r})")
        return f"--{flag.name}" if value else None
    if flag.values == -1 and isinstance(value, numbers.Number):
        value = [value]  # labels=3 is labels=[3]
    if flag.values > 1 or flag.values == -1:
        is_list = not isinstance(value, (str, bytes)) and hasattr(value, "__len__")
        if not is_list or (flag.values > 1 and len(value) != flag.values) or len(value) == 0:
            wanted = f"{flag.values} values" if flag.values > 1 else "a list of one or more values"
            raise TypeError(f"{flag.keyword}= takes {wanted} (got {value!r})")
        text = ",".join(_value_text(flag.keyword, v) for v in value)
    else:
        text = _value_text(flag.keyword, value)
    return f"--{flag.name}={text}"


def flag_arguments(
    function: str,
    table: Mapping[str, Flag],
    options: Mapping[str, object],
    *,
    allowed=None,
    excluded: Mapping[str, str] = {},
) -> List[str]:
    """The command-line arguments of keyword `options` of `function`.

    `allowed` restricts the keywords to a subset of `table`; `excluded` maps flag names that are
    not keywords of `function` to the reason (raised as TypeError). Options set to None are left
    out (the flag's default applies).
    """
    args = []
    for keyword, value in options.items():
        name = keyword.replace("_", "-")
        if name in excluded:
            raise TypeError(f"{function}() takes no {keyword}= (--{name}): {excluded[name]}")
        known = [k for k in table if allowed is None or k in allowed]
        if keyword not in known:
            close = difflib.get_close_matches(keyword, known, n=3)
            hint = f"; did you mean {', '.join(c + '=' for c in close)}?" if close else ""
            raise TypeError(f"{function}() got an unexpected keyword argument {keyword!r}{hint}")
        if value is None:
            continue
        argument = _flag_argument(table[keyword], value)
        if argument is not None:
            args.append(argument)
    return args


def keyword_docs(table: Mapping[str, Flag], keywords) -> str:
    """A numpydoc-style list of the keyword options `keywords`, from the flags' help."""
    lines = []
    for keyword in keywords:
        flag = table[keyword]
        count = f" × {flag.values}" if flag.values > 1 else " list" if flag.values == -1 else ""
        kind = "bool" if flag.values == 0 else flag.type + count
        default = f", default {flag.default}" if flag.default else ""
        lines.append(f"    {keyword} : {kind}{default}  (--{flag.name})")
        lines.append(textwrap.fill(flag.help, width=96, initial_indent=" " * 8, subsequent_indent=" " * 8))
    return "\n".join(lines)

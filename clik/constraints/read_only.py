"""Read-only views of what a constraint set is built on: sequences and arrays.

A :class:`~clik.constraints.ConstraintSet` builds its collision scene and its kinds'
rows once, from its obstacles, links and limits; both engines then read them. A
sequence changed in place behind the set's back (``cset.obstacles.append(...)``)
would leave the scene and the rows describing different obstacles, so what the set
and its kinds show is read-only: :class:`ReadOnlyList` (a tuple that reads like the
list it was, and says how to change it when written to) and :func:`read_only_array`
(a NumPy array with ``writeable = False``).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Generic, NoReturn, TypeVar

import numpy as np

from clik.errors import InputError

T = TypeVar("T")


class ReadOnlyList(tuple[T, ...], Generic[T]):
    """A tuple that compares equal to the list of the same items, and refuses changes.

    ``len``, indexing, iteration, ``in``, ``index``, ``count`` and ``+`` work as on a
    list (``+`` with a list gives a new list; a slice is a plain tuple); every method
    that would change a list (``append``, ``extend``, ``insert``, ``remove``, ``pop``,
    ``clear``, ``sort``, ``reverse``, item assignment and deletion, ``+=``, ``*=``)
    raises an :class:`~clik.errors.InputError` naming ``field`` and how to change it.

    Args:
        items: The items.
        field: The name of the sequence in the error (``"obstacles"``).
        change: How to change it, in words (``"ConstraintSet.set_obstacles([...])"``).
    """

    field: str
    change: str

    def __new__(
        cls, items: Iterable[T] = (), field: str = "sequence", change: str = "a new object"
    ) -> ReadOnlyList[T]:
        """A read-only sequence of ``items`` (see the class)."""
        out = super().__new__(cls, items)
        out.field, out.change = field, change
        return out

    def __getnewargs__(self) -> tuple[Any, ...]:
        return (tuple(self), self.field, self.change)

    def _refuse(self, *_: object, **__: object) -> NoReturn:
        raise InputError(
            self.field,
            f"a change through {self.change}, not in place (it is read-only: what was "
            "built on it would no longer match)",
        )

    append = extend = insert = remove = pop = clear = sort = reverse = _refuse
    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse

    def __eq__(self, other: object) -> bool:
        if isinstance(other, list):
            return list(self) == other
        return tuple.__eq__(self, other)

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = tuple.__hash__

    def __add__(self, other: Any) -> Any:
        if isinstance(other, list):
            return list(self) + other
        return tuple.__add__(self, other)

    def __radd__(self, other: Any) -> Any:
        if isinstance(other, list):
            return other + list(self)
        return NotImplemented

    def __repr__(self) -> str:
        return repr(list(self))


def read_only_array(value: Any, dtype: Any = float) -> np.ndarray:
    """A new array of ``value`` that cannot be written (``flags.writeable`` False)."""
    out = np.array(value, dtype=dtype)
    out.flags.writeable = False
    return out

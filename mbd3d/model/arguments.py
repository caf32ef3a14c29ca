"""The arguments a model element was made with, kept so that a model file can write it back.

Joints, drivers, force elements and motions derive from :class:`RecordsArguments`: the
constructor of the class actually made (not those of its bases, which it calls) records its
bound arguments, and :meth:`RecordsArguments.arguments` returns them. A model file is then the
list of constructor calls that built the model, whatever each class does with its arguments.
"""

from __future__ import annotations

import functools
import inspect
from typing import Any

__all__ = ["RecordsArguments"]


class RecordsArguments:
    """Mixin: instances remember the arguments of their constructor."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        original = cls.__dict__.get("__init__")
        if original is None:
            return
        signature = inspect.signature(original)

        @functools.wraps(original)
        def __init__(self, *args: Any, **kw: Any) -> None:
            # the outermost constructor records; those of the bases it calls find it done
            if "_arguments" not in self.__dict__:
                try:
                    bound = signature.bind(self, *args, **kw)
                except TypeError:
                    bound = None  # the constructor itself reports the bad call
                if bound is not None:
                    self.__dict__["_arguments"] = {
                        name: value for name, value in bound.arguments.items()
                        if name != "self"}
            original(self, *args, **kw)

        cls.__init__ = __init__

    @property
    def arguments(self) -> dict[str, Any]:
        """The constructor's arguments by name (defaults left out)."""
        return dict(self.__dict__.get("_arguments", {}))

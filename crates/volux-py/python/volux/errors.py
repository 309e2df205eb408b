"""Volux's exceptions. Each keeps the library's fields as attributes (``err.setting``,
``err.path``, ``err.bytes`` ...), and is also the built-in exception a Python user would
catch for it (a ``ValueError`` for a wrong argument, an ``OSError`` for a file that cannot
be read, a ``MemoryError`` for a memory budget exceeded).

>>> import volux
>>> try:
...     volux.open("missing.nrrd")
... except volux.ReaderError as e:
...     print(e.path)
missing.nrrd
"""

__all__ = [
    "VoluxError",
    "ReaderError",
    "OptionError",
    "SettingError",
    "Refused",
    "OverBudget",
    "GpuError",
    "Cancelled",
]


class VoluxError(Exception):
    """The base of Volux's exceptions; ``fields`` holds the error's data by name."""

    def __init__(self, message, **fields):
        super().__init__(message)
        self.message = message
        self.fields = fields
        for name, value in fields.items():
            setattr(self, name, value)

    def __str__(self):
        return self.message


class ReaderError(VoluxError, OSError):
    """A file, folder or store that cannot be read: ``path`` and ``reason``."""

    def __init__(self, message, **fields):
        OSError.__init__(self, message)
        VoluxError.__init__(self, message, **fields)


class OptionError(VoluxError, ValueError):
    """A keyword argument that does not apply, or a value it does not take: ``option``
    (and ``value``, ``expected`` where known)."""


class SettingError(VoluxError, ValueError):
    """A setting out of its range: ``setting`` (the keyword argument), ``value``,
    ``expected``."""


class Refused(VoluxError, ValueError):
    """A renderer that does not draw what was asked: ``by`` (the renderer), ``refuses``
    (what), ``remedy`` (the argument that applies the way out, or ``None``)."""


class OverBudget(VoluxError, MemoryError):
    """More memory than the budget allows: ``what``, ``bytes`` and ``limit``; raise the
    budget with ``volux.open(..., memory_budget=...)`` or the ``VOLUX_MEMORY_BUDGET``
    environment variable."""


class GpuError(VoluxError, RuntimeError):
    """The GPU backend is missing or failed: ``reason`` and ``remedy`` where known."""


class Cancelled(VoluxError):
    """A render stopped before its end (a progress callback raised, or the engine was asked
    to stop). Ctrl-C raises ``KeyboardInterrupt`` as usual."""

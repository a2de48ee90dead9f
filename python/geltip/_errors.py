"""geltip's exceptions. ``str(e)`` is the one-line message the ``geltip`` command prints
(after its ``error:`` prefix)."""


class GeltipError(Exception):
    """Base of every error geltip raises."""


class InvalidArgumentError(GeltipError, ValueError):
    """A bad argument, sensor file, object, mesh or image; the message starts with its name."""


class GpuError(GeltipError, RuntimeError):
    """No GPU adapter (or no lavapipe), a device failure or timeout, or an internal error."""


class GeltipIOError(GeltipError, OSError):
    """A file could not be read or written."""


class GeltipFileNotFoundError(GeltipIOError, FileNotFoundError):
    """A file that is not there (``except FileNotFoundError`` catches it too)."""

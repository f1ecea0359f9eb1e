"""g1patch: quad meshes to smooth bicubic patch networks, with a continuity report that proves it."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("g1patch")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__"]

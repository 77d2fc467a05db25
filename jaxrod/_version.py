"""The installed version of jaxrod (a bottom-layer module: the sweeps record it in their metadata)."""

from importlib.metadata import PackageNotFoundError, version

__all__ = ["__version__"]

try:
    __version__ = version("jaxrod")
except PackageNotFoundError:  # pragma: no cover
    __version__ = "0.0.0"

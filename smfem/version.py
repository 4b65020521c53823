"""The package version, in a module of its own: the run files record it without importing the API."""

__version__ = "0.1.0"

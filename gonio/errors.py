"""The exception hierarchy of the domain package; the CLI turns these into one line."""


class GonioError(Exception):
    """Base of every error gonio raises on purpose."""


class DomainError(GonioError, ValueError):
    """Coordinates outside a parametrization's valid domain, or malformed input arrays."""


class UnknownNameError(GonioError, KeyError):
    """A parametrization or model name that is not registered."""

    def __str__(self) -> str:  # KeyError quotes its argument; we want the plain message.
        return str(self.args[0]) if self.args else ""


class ConfigError(GonioError):
    """A configuration file that cannot be used; the message is one line per problem."""

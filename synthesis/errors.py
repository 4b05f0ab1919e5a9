"""One exception class per failure domain; the CLI maps each to an exit code (docs/ARCHITECTURE.md, "Exit codes")."""


class AgrisynthError(Exception):
    """Base of every error agrisynth reports to a user as one clear line."""

    exit_code = 2


class SpecError(AgrisynthError, ValueError):
    """The spec file is unreadable, not TOML, or a field is missing, unknown or out of range."""


class ResultError(AgrisynthError, ValueError):
    """A result.json that cannot be read: missing, truncated, not ours, or from a newer schema."""


class AssemblyError(AgrisynthError, ValueError):
    """The linkage cannot be assembled: a loop-closure triangle inequality fails."""


class SolverError(AgrisynthError, RuntimeError):
    """IPOPT failed or the rule set is infeasible; the message names the rules and IPOPT's status."""

    exit_code = 3


class OutputError(AgrisynthError):
    """The output folder cannot be written, or holds something agrisynth will not replace."""


class NothingToDraw(ValueError):
    """A kind's comparison figure has nothing to draw (e.g. no candidate has a design its model could evaluate): the
    message is the kind's own reason, shown on the page as it is."""

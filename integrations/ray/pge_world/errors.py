"""The error a user fixes: printed as one line, exit status 1."""


class WorldError(Exception):
    """A problem the user fixes (no cluster, another world in DIR, a script error...)."""

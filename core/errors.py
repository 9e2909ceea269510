"""Errors a user can fix. The CLI prints them as one line and exits with code 2."""


class InputError(Exception):
    """Bad input: the message names the key (or file) and the rule it breaks."""

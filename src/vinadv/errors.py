"""The one exception type that means "the user's input is wrong".

The CLI turns it into a one-line message and exit status 2; anything else is a bug and keeps its traceback.
"""


class InputError(ValueError):
    """Bad input: a file, field or value that is wrong. The message names it."""

"""The one exception type that means "the user's input is wrong".

The CLI turns it into a one-line message and exit status 2; anything else is a bug and keeps its traceback.
"""


class InputError(ValueError):
    """Bad input: a file, field or value that is wrong. The message names it.

    `parameters`: the library parameters the message names (say `"n"`, `"shard_size"`), in the order they
    appear in it. Library code speaks of parameters only; the command line shows the matching flags instead
    (`vinadv.commands.cli_message`).
    """

    def __init__(self, message: str, *parameters: str):
        super().__init__(message)
        self.parameters = parameters

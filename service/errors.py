"""The one exception type a user mistake becomes."""


class InputError(Exception):
    """Bad input from the user: the message is one line naming the problem.

    The CLI and the HTTP layer turn it into a one-line error (exit code 2, or an
    HTTP 4xx), never a traceback.
    """

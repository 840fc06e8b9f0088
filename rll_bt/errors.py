"""Errors a user can cause.  The command line turns them into one clear
message and an exit code, never a traceback."""
from __future__ import annotations


class UserError(Exception):
    """Bad input from the user: a file, a value, an argument.

    ``where`` names the file (and line/column) or the value at fault;
    ``hint`` says what to do about it.
    """

    exit_code = 2

    def __init__(self, message: str, where: str | None = None, hint: str | None = None):
        super().__init__(message)
        self.message = message
        self.where = where
        self.hint = hint

    def __str__(self) -> str:
        text = f"{self.where}: {self.message}" if self.where else self.message
        if self.hint:
            text += f"\n  hint: {self.hint}"
        return text


class Unavailable(UserError):
    """A device, port, host or peer could not be reached."""

    exit_code = 3

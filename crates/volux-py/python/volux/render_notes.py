"""Notes a user should read, said as warnings (``UserWarning``)."""

import warnings


def say_notes(notes):
    """Warns each note once."""
    for note in notes:
        warnings.warn(note, stacklevel=3)

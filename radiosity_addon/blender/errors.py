"""The one exception type of the Blender side: a bake the user's scene cannot make."""


class BakeError(RuntimeError):
    """Refused or failed bake; the message is one line that says what to do."""

"""The exception the compiled module raises for bad input (its C++ InputError)."""


class SceneError(ValueError):
    """A scene, study or method parameter that Penumbra's reader refuses.

    The same check and message as the command line's exit-2 error:
    ``str(e)`` is what ``penumbra`` prints after ``penumbra: error: ``.
    Attributes: ``file`` (the file, or the origin such as ``pn.factor``),
    ``pointer`` (the JSON pointer, ``""`` where none applies) and
    ``reason`` (what was expected, without file and pointer).
    """

    def __init__(self, message, file="", pointer="", reason=""):
        super().__init__(message)
        self.file = file
        self.pointer = pointer
        self.reason = reason

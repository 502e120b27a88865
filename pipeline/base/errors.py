"""The errors a user meets, in one place: each names the file, the field (or
the result) and the reason.  Imported by the layers that raise them; nothing
here imports the rest of the package."""


class StudyError(ValueError):
    """A study file is wrong: names the file, the field and the reason."""

    def __init__(self, file, where, reason):
        self.file = str(file)
        self.field = where
        self.reason = reason
        super().__init__(f"{file}: {where}: {reason}" if where else f"{file}: {reason}")


class ResultsError(ValueError):
    """A results file cannot be used: names the file and the reason."""

    def __init__(self, path, reason):
        self.path = str(path)
        super().__init__(f"{path}: {reason}")

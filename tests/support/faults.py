"""What the fault tests check after a fault: a file's bytes, and a command
line's ending (one line, no traceback, naming what it must)."""

import hashlib
from pathlib import Path


def digest(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def one_line_error(capsys, *needles):
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err, err
    assert len(err.splitlines()) == 1, err
    for n in needles:
        assert str(n) in err, (n, err)
    return err

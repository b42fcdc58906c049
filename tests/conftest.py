"""Shared fixtures: a CLI runner that returns (exit status, stdout, stderr)."""

from __future__ import annotations

import pytest

from diefab.cli import main


@pytest.fixture
def run(capsys):
    """Run ``diefab ARGS...`` in-process; returns (status, stdout, stderr)."""

    def _run(*args: str) -> tuple[int, str, str]:
        try:
            main([str(a) for a in args])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        else:  # pragma: no cover - main always exits
            code = 0
        out, err = capsys.readouterr()
        return code, out, err

    return _run


@pytest.fixture
def bad(run):
    """Assert ``diefab ARGS...`` fails with exit 2 and one line on stderr; return that line."""

    def _bad(*args: str) -> str:
        code, _, err = run(*args)
        assert code == 2, err
        lines = err.strip().splitlines()
        assert len(lines) == 1, err
        assert "Traceback" not in err
        return lines[0]

    return _bad

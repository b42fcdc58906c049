"""What a part of the page (a tab, the 3D view) may use of the page that holds it."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Protocol

from diefab.dice.design import Design
from diefab.studio.state import Session


class Host(Protocol):
    """The page (:class:`diefab.studio.app.Studio`) as its tabs see it.

    Attributes
    ----------
    session : Session
        The die being edited.
    out_dir : Path
        The only folder the page writes into (and reads roll videos from).
    evaluation : dict or None
        What the page shows now (:func:`diefab.studio.state.evaluate`).
    client : nicegui.Client
        The browser tab.
    """

    session: Session
    out_dir: Path
    evaluation: dict[str, Any] | None
    client: Any

    def show_error(self, message: str) -> None:
        """Show one line of error at the top of the page."""

    def open_design(self, design: Design) -> None:
        """Open `design` in the page (undoable)."""

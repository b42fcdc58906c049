"""``diefab studio``: design, see and make a die in a local web page.

:mod:`.state` holds the die being edited and what the page shows of it,
:mod:`.view` the geometry drawn, :mod:`.jobs` the worker processes of long
work, :mod:`.make` the files written, :mod:`.app` the page itself (NiceGUI,
imported only when the studio is served).
"""

from diefab.studio.state import Session, evaluate, face_colors, parameters

__all__ = ["Session", "evaluate", "face_colors", "parameters"]

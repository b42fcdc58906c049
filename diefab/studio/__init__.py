"""``diefab studio``: design, see and make a die in a local web page.

Without a web page: :mod:`.state` holds the die being edited and its
evaluation, :mod:`.view` the geometry drawn, :mod:`.chart` what the charts
and tables show, :mod:`.jobs` the worker processes of long work,
:mod:`.make` and :mod:`.files` the files written and read.

The page (NiceGUI, imported only when the studio is served): :mod:`.app`
its layout and how an edit reaches it, :mod:`.scene` the 3D die
(``die.js``), :mod:`.make_panel`, :mod:`.job_panels` and
:mod:`.camera_panel` its tabs, :mod:`.host` what a tab may use of the page.
"""

from diefab.studio.state import Session, evaluate, face_colors, parameters

__all__ = ["Session", "evaluate", "face_colors", "parameters"]

"""File formats of a printed die: binary STL and a two-colour 3MF package."""

from __future__ import annotations

import io
import zipfile
from typing import TYPE_CHECKING

import numpy as np

from diefab.core.errors import FabricationError

if TYPE_CHECKING:
    from diefab.fabricate.stl import Solid

__all__ = ["BODY_COLOR", "LABEL_COLOR", "inlay_stl_bytes", "stl_bytes", "threemf_bytes", "threemf_mesh"]

#: The 3MF core namespace.
CORE_NS = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"


def stl_bytes(solid: Solid) -> bytes:
    """Binary STL of the body, millimetres, bed face down."""
    return _stl(solid.print_vertices, solid.triangles, f"diefab {solid.design.name} mm")


def inlay_stl_bytes(solid: Solid) -> bytes:
    """Binary STL of the labels alone (:attr:`Solid.inlay`), placed as on the body's print bed.

    Raises
    ------
    FabricationError
        If the die has no labels.
    """
    if solid.inlay is None:
        raise FabricationError(f"design {solid.design.name!r} has no labels to write as an inlay")
    vertices, triangles = solid.inlay
    return _stl(solid.on_bed(vertices), triangles, f"diefab {solid.design.name} labels mm")


def _stl(vertices: np.ndarray, triangles: np.ndarray, title: str) -> bytes:
    tri = vertices[triangles]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])
    data = np.zeros(len(tri), dtype=record)
    data["normal"] = normals
    data["vertices"] = tri
    header = title.encode("ascii", "replace")[:80].ljust(80, b" ")
    return header + np.uint32(len(tri)).tobytes() + data.tobytes()


_CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
    '<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
    "</Types>"
)
_RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>'
    "</Relationships>"
)


#: Display colours of the 3MF's two materials (sRGB with alpha).
BODY_COLOR = "#F2EBD9FF"
LABEL_COLOR = "#1F3373FF"


def threemf_bytes(solid: Solid) -> bytes:
    """3MF package (core specification, unit millimetre): the die as one object of two coloured parts.

    The body (pockets empty, no raised text) and the labels (:attr:`Solid.inlay`)
    are two closed shells of one object's mesh; every triangle names its base
    material (body or labels, each with a display colour), and PrusaSlicer's
    ``Metadata/Slic3r_PE_model.config`` names the two triangle ranges as the
    object's two parts, on extruders 1 and 2, so a multi-material printer
    prints the values (and markers) in a second colour; a single-extruder
    printer prints both parts with its one extruder.  A die without labels is one shell.
    """
    from xml.sax.saxutils import escape, quoteattr

    name = escape(solid.design.name, {'"': "&quot;"})  # element text and attribute values alike
    parts = (
        [("body", *solid.base), ("labels", *solid.inlay)]
        if solid.inlay is not None and solid.base
        else [("body", solid.vertices, solid.triangles)]
    )
    verts, tris, ranges, offset, first = [], [], [], 0, 0
    for index, (part, vertices, triangles) in enumerate(parts):
        verts.extend(f'<vertex x="{x:.6f}" y="{y:.6f}" z="{z:.6f}"/>' for x, y, z in solid.on_bed(vertices))
        tris.extend(
            f'<triangle v1="{a + offset}" v2="{b + offset}" v3="{c + offset}" pid="1" p1="{index}"/>'
            for a, b, c in triangles
        )
        ranges.append((part, first, first + len(triangles) - 1))
        offset, first = offset + len(vertices), first + len(triangles)
    materials = (
        f'<basematerials id="1"><base name="body" displaycolor={quoteattr(BODY_COLOR)}/>'
        f'<base name="labels" displaycolor={quoteattr(LABEL_COLOR)}/></basematerials>'
    )
    model = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<model unit="millimeter" xml:lang="en-US" '
        f'xmlns="{CORE_NS}" '
        'xmlns:slic3rpe="http://schemas.slic3r.org/3mf/2017/06">'
        '<metadata name="slic3rpe:Version3mf">1</metadata>'
        f'<metadata name="Title">{name}</metadata>'
        '<metadata name="Application">diefab</metadata>'
        f'<resources>{materials}<object id="2" type="model" name="{name}" pid="1" pindex="0">'
        f"<mesh><vertices>{''.join(verts)}</vertices><triangles>{''.join(tris)}</triangles></mesh></object>"
        '</resources><build><item objectid="2"/></build></model>'
    )
    volumes = "".join(
        f'<volume firstid="{lo}" lastid="{hi}"><metadata type="volume" key="name" value="{name} {part}"/>'
        f'<metadata type="volume" key="extruder" value="{index + 1}"/>'
        '<metadata type="volume" key="volume_type" value="ModelPart"/></volume>'
        for index, (part, lo, hi) in enumerate(ranges)
    )
    config = (
        '<?xml version="1.0" encoding="UTF-8"?>\n<config><object id="2" instances_count="1">'
        f'<metadata type="object" key="name" value="{name}"/>{volumes}</object></config>'
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("[Content_Types].xml", _CONTENT_TYPES)
        zf.writestr("_rels/.rels", _RELS)
        zf.writestr("3D/3dmodel.model", model)
        zf.writestr("Metadata/Slic3r_PE_model.config", config)
    return buf.getvalue()


def threemf_mesh(data: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The one object of a 3MF package written by :func:`threemf_bytes`, read back.

    Returns
    -------
    vertices : (n, 3) float
        Millimetres.
    triangles : (m, 3) int
        Indices into `vertices`.
    part : (m,) int
        Each triangle's material: 0 the body, 1 the labels (and markers).
    """
    import xml.etree.ElementTree as ET

    root = ET.fromstring(zipfile.ZipFile(io.BytesIO(data)).read("3D/3dmodel.model"))
    ns = {"m": CORE_NS}
    (obj,) = root.iterfind(".//m:object", ns)
    vertices = np.array([[float(v.get(k)) for k in "xyz"] for v in obj.iterfind(".//m:vertex", ns)])
    triangles = list(obj.iterfind(".//m:triangle", ns))
    indices = np.array([[int(t.get(k)) for k in ("v1", "v2", "v3")] for t in triangles])
    part = np.array([int(t.get("p1")) for t in triangles])
    return vertices, indices, part

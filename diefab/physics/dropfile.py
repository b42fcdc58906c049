"""A file of finished drops, so that a stopped validation continues where it stopped.

Drop *i*'s outcome depends only on the die's body, the physics settings, the
seed and *i* (:func:`~diefab.physics.simulate.simulate` draws its initial
conditions from ``SeedSequence(seed, spawn_key=(i,))``), so the drops a stopped
run finished are the drops a whole run would give, and a run asked for more
drops than a file holds continues the same sequence.  A :class:`DropFile`
keeps each drop's outcome, :data:`UNKNOWN` for a drop not yet run, with the
identity of what made them (:func:`drops_identity`): a file made by another
die, fill, physics, seed or engine is refused, never mixed in.

The file is a NumPy ``.npz`` archive (read without pickles) with three
arrays: ``format``, ``identity`` and ``outcomes``.
:mod:`diefab.physics.checkpoint` runs drops kept in such files.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "drops.npz"
>>> f = DropFile(path)
>>> f.load("abc", 4, faces=3).tolist() == [UNKNOWN] * 4
True
>>> f.save("abc", np.array([2, 0, UNKNOWN, 1], dtype=np.int32))
>>> f.load("abc", 6, faces=3).tolist() == [2, 0, UNKNOWN, 1, UNKNOWN, UNKNOWN]
True
"""

from __future__ import annotations

import hashlib
import io
import json
import zipfile
import zlib
from pathlib import Path

import numpy as np

from diefab.core.errors import PhysicsError

__all__ = ["UNKNOWN", "DropFile", "drops_identity"]

#: The outcome of a drop not yet run (the engine's own codes are a face index, -1 cocked and -2 unsettled).
UNKNOWN = -100
#: The file format this module writes and reads.
FORMAT = 1
#: Largest drop file read, and most it may unpack to: four bytes per drop of the largest run, and room for headers.
MAX_BYTES = 4 * 100_000_000 + 1_000_000


def drops_identity(design, settings, seed: int) -> str:
    """A digest of what decides every drop's outcome: the die's body, the settings, the seed and the engine.

    The body is the one :func:`~diefab.physics.simulate.simulate` drops: the
    design's shape, mass and inertia as made (its fill), in the principal
    frame, with its face order; `settings` is a
    :class:`~diefab.dice.drop.PhysicsSettings`.
    """
    from importlib.metadata import PackageNotFoundError, version

    from diefab.physics.world import OUTCOME_VERSION, die_body

    body = die_body(design.polyhedron, design.mass_properties())
    try:
        engine = version("pybullet")
    except PackageNotFoundError:  # pragma: no cover - pybullet is a dependency
        engine = "unknown"
    digest = hashlib.sha256()
    head = {"settings": settings.as_dict(), "seed": int(seed), "outcome_version": OUTCOME_VERSION, "pybullet": engine}
    digest.update(json.dumps(head, sort_keys=True).encode("utf-8"))
    for array in (body.vertices, body.normals, body.heights, body.inertia, np.array([body.mass])):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    for face in body.faces:
        digest.update(np.asarray(face, dtype=np.int64).tobytes() + b";")
    return digest.hexdigest()


class DropFile:
    """The drop file at `path`: :meth:`load` what it holds, :meth:`save` more."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)

    def load(self, identity: str, n: int, *, faces: int) -> np.ndarray:
        """(max(n, held),) int32: the outcomes held, :data:`UNKNOWN` beyond them; all unknown if there is no file.

        Raises
        ------
        PhysicsError
            The file is not a drop file, is corrupt, or was made by another
            die, physics, seed or engine (`identity`).
        """
        from diefab.physics.world import UNSETTLED

        if not self.path.exists():
            return np.full(n, UNKNOWN, dtype=np.int32)
        fmt, held_identity, held = self._read()
        if fmt != FORMAT:
            raise PhysicsError(f"drop file {self.path} has format {fmt}, not {FORMAT}")
        if held_identity != identity:
            raise PhysicsError(f"drop file {self.path} holds the drops of another die, fill, physics, seed or "
                               "engine version: name another file for this validation")  # fmt: skip
        if (
            held.ndim != 1
            or held.dtype.kind not in "iu"
            or np.any((held != UNKNOWN) & ((held < UNSETTLED) | (held >= faces)))
        ):
            raise PhysicsError(f"drop file {self.path} is corrupt (its outcomes are not drop outcomes)")
        held = held.astype(np.int32)
        if held.size >= n:
            return held
        return np.concatenate([held, np.full(n - held.size, UNKNOWN, dtype=np.int32)])

    def count(self) -> int:
        """The drops the file holds (0 if there is no file), whatever die they are of."""
        if not self.path.exists():
            return 0
        return int(np.count_nonzero(self._read()[2] != UNKNOWN))

    def _read(self) -> tuple[int, str, np.ndarray]:
        """The file's format, identity and outcomes, read within the size limits."""
        from diefab.core.files import check_size

        if not self.path.is_file():
            raise PhysicsError(f"drop file {self.path} is not a regular file")
        check_size(self.path, MAX_BYTES, f"drop file {self.path}", PhysicsError)
        try:
            with open(self.path, "rb") as fh:
                with zipfile.ZipFile(fh) as members:  # what it unpacks to, before unpacking it
                    unpacked = sum(member.file_size for member in members.infolist())
                if unpacked > MAX_BYTES:
                    raise PhysicsError(f"drop file {self.path} unpacks to {unpacked:,} bytes, more than the "
                                       f"{MAX_BYTES:,} of the largest run")  # fmt: skip
                fh.seek(0)
                archive = np.load(fh, allow_pickle=False)
                if not hasattr(archive, "files"):  # one array (.npy), not an archive
                    raise ValueError("not an archive")
                with archive:
                    fmt, held_identity, held = archive["format"], archive["identity"], archive["outcomes"]
                    return int(fmt), str(held_identity), np.array(held)
        except PhysicsError:
            raise
        except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile, zlib.error):
            raise PhysicsError(f"drop file {self.path} is not a diefab drop file (a NumPy archive of its format, "
                               "identity and outcomes): remove it or name another") from None  # fmt: skip

    def save(self, identity: str, outcomes: np.ndarray) -> None:
        """Write `outcomes` (:data:`UNKNOWN` for drops not run) with `identity`, atomically, even after a stop."""
        from diefab.core.files import keep_state

        buffer = io.BytesIO()
        np.savez_compressed(buffer, format=np.int64(FORMAT), identity=np.str_(identity),
                            outcomes=np.asarray(outcomes, dtype=np.int32))  # fmt: skip
        keep_state(self.path, buffer.getvalue())

"""Built-in drives: motor files shipped with bldclab.

``htm-48v``: paper 1 Table II. ``htm-48v-losses``: the same drive with the losses of a real inverter (onsemi NTB5860NL
MOSFETs, datasheet values) and core (EN 10106 grade M270-35A). ``f60prov-2550kv``: a 5-inch racing-drone motor (T-Motor
F60PRO V 2207.5 KV2550, 4S) from the parameters its maker supplied. ``mn3110-780kv``: an 11-inch multirotor motor
(T-Motor MN3110 KV780, 4S) from CTU MRS's bench tables. ``lu-4kw``: paper 2 appendix with a synthetic non-ideal
back-EMF (see :mod:`bldclab.model.catalog.synthetic` for how it is made). ``outrunner-24v``: a 24 V, 21-pole-pair
outrunner with a sinusoidal back-EMF, from the motor parameters of Ben Katz's open-source Mini Cheetah
motor-controller firmware. ``servo-2k2``: a 540 V, 2.2 kW PMSM with a sinusoidal back-EMF and 51 mH, from the
motulator examples. Each file cites the source of every number and says which are assumed (``docs/motor-files.md``).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from ...errors import BldclabError
from ..motor import Drive

__all__ = ["load", "names"]


def names() -> list[str]:
    """Return the names of the built-in drives."""
    files = resources.files(__name__)
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def load(name_or_path: str | Path) -> Drive:
    """Load a built-in drive by name, or a motor file by path.

    Parameters
    ----------
    name_or_path : str or Path
        A catalog name (``bldclab.model.catalog.names()``) or the path of a TOML motor file.

    Returns
    -------
    Drive

    Raises
    ------
    BldclabError
        If the name is neither a catalog entry nor an existing file, or the file is invalid.

    """
    key = str(name_or_path)
    if key in names():
        with resources.as_file(resources.files(__name__) / f"{key}.toml") as p:
            return Drive.from_toml(p)
    path = Path(key)
    if path.is_file():
        return Drive.from_toml(path)
    raise BldclabError("MOTOR", f"{key!r} is neither a built-in drive ({', '.join(names())}) nor a file")

"""pkm: kinematics and accuracy of parallel, hybrid and serial machine tools and robots.

The Python face of the pkm library (Rust). Load a machine, then call its kinematics
on numpy arrays and its analyses::

    import pkm, numpy as np
    m = pkm.load("examples/machines/hexapod-linuxcnc.toml")
    q, reachable, limit = m.ik(poses)          # poses: (N, 6) array, mm and rad

Units: millimetres and radians in and out of arrays; seconds for time. Limit
violations and summaries carry their own unit (deg for angles, as the `pkm` command
prints them).

Errors are ``pkm.Error`` and its subclasses, with pkm's messages (file, line and
field for machine files; the violated limit and by how much for unreachable poses).

Design sweeps on a Dask cluster: ``pkm.sweep`` (needs the ``sweep`` extra).
"""

from ._pkm import (  # noqa: F401
    __version__,
    Machine,
    IkBatch,
    FkBatch,
    load,
    machine_types,
    simulate_measurements,
    calibrate,
    Error,
    MachineFileError,
    InvalidInputError,
    UnreachableError,
    NotAttainableError,
    NotConvergedError,
    NotIdentifiableError,
    SingularError,
    UnsupportedError,
)

__all__ = [
    "Machine",
    "IkBatch",
    "FkBatch",
    "load",
    "machine_types",
    "simulate_measurements",
    "calibrate",
    "Error",
    "MachineFileError",
    "InvalidInputError",
    "UnreachableError",
    "NotAttainableError",
    "NotConvergedError",
    "NotIdentifiableError",
    "SingularError",
    "UnsupportedError",
]

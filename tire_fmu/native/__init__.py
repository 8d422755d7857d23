"""The reduced model as a self-contained C FMU: FMI 2.0 co-simulation, no Python on the host.

- :mod:`.codegen`: the export's declaration (variables with their fixed values, GUID,
  description) and the C sources, the model as ``static const double`` tables;
- :mod:`.runtime`: the FMI 2.0 runtime in C, the same for every export;
- :mod:`.builder`: ``build_native_fmu(reduced, out)`` writes the model description, compiles
  the sources with the local C compiler for linux64 and packs binary and sources.

See docs/native.md. ``tire-fmu export --format fmu OUT.fmu`` is the command-line way in.
"""

from .builder import NativeBuildError, build_native_fmu
from .codegen import DEFAULT_MODEL_IDENTIFIER, NativeModel, native_model

__all__ = [
    "DEFAULT_MODEL_IDENTIFIER",
    "NativeBuildError",
    "NativeModel",
    "build_native_fmu",
    "native_model",
]

"""The native C FMU: FMI 2.0 co-simulation in C, no Python on the host.

The C (``tire_fmu/native/c``, package data) builds the model itself at
``fmi2ExitInitializationMode`` from its parameters: validation with the Python FMU's messages,
the critical speed, the free ring order by order, the static footprint, the road windows; then
it steps with the unilateral contact exactly as :class:`tire_fmu.core.contact_dynamics.
ContactSimulator` does. :mod:`.builder` writes the generated headers, the model description and
the linux64 and win64 binaries into one ``.fmu``. See docs/native.md; ``tire-fmu export
--format fmu OUT.fmu`` is the command-line way in. The in-plane tire's native FMU
(TireInPlaneNative, TireInPlane.fmu's variables) is built by the same path:
``build_native_inplane_fmu``, or ``tire-fmu build-fmu --inplane --native``.
"""

from importlib import import_module

__all__ = [
    "DEFAULT_MODEL_IDENTIFIER",
    "INPLANE_MODEL_IDENTIFIER",
    "NativeBuildError",
    "build_native_fmu",
    "build_native_inplane_fmu",
    "default_platforms",
    "parameter_start_values",
]


def __getattr__(name: str):
    # the builder (and the FMU spec it writes) loads only when asked for: the compiled step
    # kernel (.kernel) is imported at an FMU's start-up, and needs none of it
    if name in __all__:
        return getattr(import_module(".builder", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

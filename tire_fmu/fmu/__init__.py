"""The tire as an FMI 2.0 co-simulation FMU (pythonfmu), a thin adapter over :mod:`tire_fmu.core`.

- :mod:`.slave`: the ``TireModal`` slave. Parameters are validated, and the reduced basis is
  built, when initialisation ends; ``do_step`` hands the inputs to the core's simulator.
- :mod:`.builder`: ``build_fmu(out_dir)`` writes ``TireModal.fmu`` with the core shipped in
  ``resources/`` and a model description that passes ``fmpy validate``; its Linux binary is
  ``pythonfmu_guard.c`` in front of pythonfmu's wrapper (statuses, messages, resource paths,
  process exit: see that file).

Neither module is imported here, so the CLI works without pythonfmu installed.
"""

"""Which module implements each ``tire-fmu`` command, and its one-line help.

Kept free of numpy and scipy: ``tire-fmu --help`` lists the commands from this table alone,
and a command's module (with the physics core behind it) is imported only when it is used.
"""

from __future__ import annotations

#: command -> (module in tire_fmu.cli, help line), in the order --help lists them
COMMANDS: dict[str, tuple[str, str]] = {
    "modes": ("ring", "natural frequencies, damping and labelled mode shapes"),
    "inplane-modes": ("inplane", "modes of the full in-plane ring: radial, tangential and "
                      "rotational, rim held or free"),
    "inplane-speed-sweep": ("inplane", "ground-frame frequencies of the in-plane ring per "
                            "order vs speed: the rolling split, with the tangential motion"),
    "inplane-cleat": ("inplane", "the in-plane tire over a cleat, axle held: Fx, Fz and My "
                      "against time, their spectra"),
    "inplane-frf": ("inplane_linear", "frequency response of the in-plane tire linearised at "
                    "its operating point: torque, rim or road to Fx, Fz, My (Bode plot)"),
    "inplane-reduce": ("inplane_linear", "balanced reduction of the linearised in-plane tire, "
                       "its error report; write it as .npz or .mat"),
    "analytic": ("ring", "closed-form frequencies of the undeformed ring (eq. 12)"),
    "patch": ("ring", "static footprint for a load (or a deflection): length, pressure, "
              "stiffness"),
    "convergence": ("ring", "FDM frequencies vs number of elements against the exact ones "
                    "(Fig. 14)"),
    "patch-sweep": ("ring", "split of the mode pairs vs contact-patch length (Fig. 17)"),
    "dispersion": ("rolling", "ground-frame frequency vs signed wavenumber at one speed "
                   "(Fig. 18)"),
    "speed-sweep": ("rolling", "ground-frame frequencies vs speed, undeformed and loaded "
                    "(Fig. 19)"),
    "cleat": ("cleat", "rim load over a cleat or pothole against the mesh, rim held "
              "(convergence of the contact points)"),
    "critical-speed": ("rolling", "standing-wave speed of the mesh and why it depends on N"),
    "frf": ("reduce", "frequency response of the full model, and of a reduced one (Bode plot)"),
    "reduce": ("reduce", "build a reduced model and report its size and accuracy"),
    "export": ("reduce", "write a reduced model: .npz (with metadata), MATLAB .mat "
               "(A, B, C, D) or a native C FMU (.fmu)"),
    "build-fmu": ("fmu", "build TireModal.fmu, the FMI 2.0 co-simulation FMU"),
    "fit": ("fit", "identify tire data from measured natural frequencies"),
    "road": ("road", "road files for road_file: cleats (SAE J2730, J2705), potholes, ISO 8608 "
             "roads as OpenCRG or profile files; read one back"),
}


def command_help(name: str) -> str:
    return COMMANDS[name][1]

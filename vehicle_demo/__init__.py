"""vehicle_demo: a quarter car co-simulated with ``TireModal.fmu`` through fmpy.

Run ``python -m vehicle_demo [--out DIR] [--quick]`` for the end-to-end demo (ride transfer
functions to 300 Hz against the full-model and spring-damper references, an ISO 8608 road run
and a cleat), ``python -m vehicle_demo sweep ...`` for a dask sweep. Modules:

- :mod:`.quarter_car`: parameters, analytic frequencies, frequency-domain references
- :mod:`.quarter_car_fmu`: the quarter car as a pythonfmu slave, and its builder
- :mod:`.cosim`: the master algorithm over the two FMUs (fmpy)
- :mod:`.coupling`: the coupling's step-size limit (spectral radius of one step)
- :mod:`.road`: ISO 8608 random road, cleat
- :mod:`.transfer`: multisine excitation, H1 and coherence, resonance identification
- :mod:`.sweep`: design of experiments on dask
- :mod:`.plots`, :mod:`.demo`: figures and the end-to-end job

Importing the package imports nothing heavy, so ``__main__`` can set up the process first.
"""

__version__ = "0.1.0"

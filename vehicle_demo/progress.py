"""Progress bars of the demos' long runs (tqdm, imported when a bar is made)."""

from __future__ import annotations


def step_bar(total: int, enabled: bool, what: str):
    """A bar over ``total`` steps, off when ``enabled`` is false."""
    from tqdm.auto import tqdm

    return tqdm(total=total, disable=not enabled, desc=what, unit="step", unit_scale=True,
                mininterval=0.5)


def advance(bar, every: int = 500):
    """A ``progress(i, steps)`` callback that moves ``bar`` to step i (redrawn every
    ``every`` steps and at the end, so that the callback costs nothing per step)."""
    def progress(i, steps):
        bar.n = i
        if i == steps or i % every == 0:
            bar.refresh()

    return progress

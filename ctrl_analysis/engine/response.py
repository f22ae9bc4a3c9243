"""The result of a :class:`~ctrl_analysis.engine.loop.Loop` simulation: every signal by name, over the batch."""

from __future__ import annotations

import numpy as np

from .._validate import check_int
from .simresult import SimResult

__all__ = ["LoopResponse"]


class LoopResponse(SimResult):
    """A :class:`~ctrl_analysis.simulate.SimResult` that also keeps every signal by name.

    Attributes
    ----------
    signals : dict of str -> ndarray, shape (N+1, B)
        Every signal at every sample instant (external inputs included).
    states : dict of str -> ndarray, shape (N+1, B, n)
        Each block's states (views into ``x``), when stored.
    final_states : dict of str -> ndarray, shape (B, n)
        Each block's state at the last instant (also when the trajectory is not stored), e.g. the
        ``x0`` of a continuation.
    """

    def __init__(self, *, signals, slices, external, outlist, state_names, x_final=None, diverged_where=None,
                 where_names=None, **kw):
        super().__init__(**kw)
        #: per run: the index in ``where_names`` of the state or signal that first went bad (-1: none)
        self.diverged_where = (np.full(self.runs, -1, dtype=int) if diverged_where is None
                               else np.asarray(diverged_where, dtype=int))
        self.where_names = list(where_names or [])
        self.signals = signals
        self.x_final = x_final
        self._slices = slices
        self.external = external
        self.outlist = outlist
        self.state_names = state_names

    @property
    def states(self) -> dict:
        """Each block's state trajectory (views into ``x``; empty when states were not stored).

        Returns
        -------
        dict of str -> numpy.ndarray, shape (N+1, B, n)
        """
        if self.x is None:
            return {}
        return {name: self.x[:, :, sl] for name, sl in self._slices.items()}

    @property
    def final_states(self) -> dict:
        """Each block's state at the last instant, also when the trajectory was not stored.

        Returns
        -------
        dict of str -> numpy.ndarray, shape (B, n)
            Ready to pass as ``x0`` to continue the simulation (with ``t0`` the last instant).
        """
        if self.x_final is None:
            return {}
        return {name: self.x_final[:, sl] for name, sl in self._slices.items()}

    def divergences(self) -> list[dict]:
        """One record per diverged run: ``run``, ``step``, ``t``, ``seed`` and ``where``.

        ``where`` names what went bad first: a state (``block.state``) that left the bound or is not finite, or a
        signal that is not finite (``block.signal (output of block 'block')``, or an input of the loop).

        Returns
        -------
        list of dict
        """
        out = super().divergences()
        for rec in out:
            code = int(self.diverged_where[rec["run"]])
            rec["where"] = self.where_names[code] if 0 <= code < len(self.where_names) else None
        return out

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; signals are {sorted(self.signals)}") from None

    def to_timeresponse(self, run: int = 0, outputs=None):
        """One run as a ``control.TimeResponseData``.

        Parameters
        ----------
        run : int
            Which run of the batch (0-based).
        outputs : sequence of str, optional
            Signals to report as outputs (default: the loop's ``outputs``).

        Returns
        -------
        control.TimeResponseData
            Time, outputs, the loop's states (when stored) and its external inputs.
        """
        import control as ct

        run = check_int("run", run, minimum=0, maximum=self.runs - 1)
        outs = list(self.outlist if outputs is None else outputs)
        y = np.stack([self[n][:, run] for n in outs])
        u = np.stack([self[n][:, run] for n in self.external]) if self.external else None
        x = self.x[:, run, :].T if self.x is not None else None
        return ct.TimeResponseData(self.t, y, x, u, output_labels=outs,
                                   input_labels=list(self.external) or None,
                                   state_labels=self.state_names if x is not None else None,
                                   issiso=False)

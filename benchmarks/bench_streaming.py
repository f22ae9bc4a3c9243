"""Streamed statistics against holding every run: time and peak memory (tracemalloc).

``R`` runs of an ``S``-sample trace arrive in chunks of ``C`` runs (seeded normal draws, the same
in both methods). *streamed*: each chunk goes into a :class:`~ctrl_analysis.streaming.Moments`
and a :class:`~ctrl_analysis.streaming.Quantiles` and is dropped. *held*: the chunks are stored
into one ``(R, S)`` array, then numpy's mean, std, min, max and quantiles along the runs. Both
report the same statistics (mean, std, min, max, the 5/50/95 % quantiles per sample). Printed:
seconds (``time.perf_counter``; the draws alone timed apart), the peak of traced memory, the
largest difference of mean and std (relative to the std), and the worst rank error of the streamed quantiles
(their rank among the held values, over every sample) beside the proven bound.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_streaming.py [--runs R] [--chunk C] [--samples S] [--k K]

(defaults: 10**6 runs, chunks of 1000, 100 samples, k = 4096).
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import _common  # noqa: F401  (before numpy: one BLAS thread, the repository on sys.path)
import numpy as np

from ctrl_analysis.streaming import Moments, Quantiles

Q = np.array([0.05, 0.5, 0.95])


def chunks(runs: int, chunk: int, samples: int, seed: int = 0):
    """The runs, ``chunk`` at a time: a seeded random walk per run (a trace), seed by chunk."""
    for i, start in enumerate(range(0, runs, chunk)):
        rng = np.random.default_rng([seed, i])
        yield np.cumsum(rng.normal(size=(min(chunk, runs - start), samples)), axis=1)


def draws_only(runs, chunk, samples, k):
    for _ in chunks(runs, chunk, samples):
        pass


def streamed(runs, chunk, samples, k):
    m, q = Moments(), Quantiles(k=k)
    for c in chunks(runs, chunk, samples):
        m.add(c)
        q.add(c)
    return dict(mean=m.mean, std=m.std(), min=m.min, max=m.max, q=q.quantile(Q), bound=q.rank_error,
                nbytes=m.nbytes + q.nbytes)


def held(runs, chunk, samples, k):
    x = np.empty((runs, samples))
    for i, c in enumerate(chunks(runs, chunk, samples)):
        x[i * chunk:i * chunk + len(c)] = c
    out = dict(mean=x.mean(axis=0), std=x.std(axis=0), min=x.min(axis=0), max=x.max(axis=0),
               q=np.quantile(x, Q, axis=0), nbytes=x.nbytes)
    out["x"] = x
    return out


def measure(fn, *args):
    """Seconds and traced peak bytes of ``fn(*args)``, and its result."""
    tracemalloc.start()
    t0 = time.perf_counter()
    out = fn(*args)
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return seconds, peak, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1_000_000)
    ap.add_argument("--chunk", type=int, default=1000)
    ap.add_argument("--samples", type=int, default=100)
    ap.add_argument("--k", type=int, default=4096)
    a = ap.parse_args()
    args = (a.runs, a.chunk, a.samples, a.k)
    t_draw, p_draw, _ = measure(draws_only, *args)
    t_s, p_s, s = measure(streamed, *args)
    t_h, p_h, h = measure(held, *args)
    x = h.pop("x")
    rel = max(np.max(np.abs(s[key] - h[key]) / h["std"]) for key in ("mean", "std"))
    exact = all(np.array_equal(s[key], h[key]) for key in ("min", "max"))
    worst = 0.0
    for j in range(a.samples):  # the rank of each streamed quantile among the held values
        col = np.sort(x[:, j])
        lo, hi = np.searchsorted(col, s["q"][:, j], "left"), np.searchsorted(col, s["q"][:, j], "right")
        worst = max(worst, float(np.max(np.maximum(lo - Q * a.runs, Q * a.runs - hi)) / a.runs))
    print(f"{a.runs} runs x {a.samples} samples, chunks of {a.chunk}, k = {a.k}, one BLAS thread")
    print(f"draws alone: {t_draw:.2f} s, peak {p_draw / 2**20:.1f} MiB")
    print("| method | seconds | seconds less the draws | peak traced memory (MiB) | held by the statistics (MiB) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for name, t, p, out in (("streamed (Moments + Quantiles)", t_s, p_s, s), ("held array + numpy", t_h, p_h, h)):
        print(f"| {name} | {t:.2f} | {t - t_draw:.2f} | {p / 2**20:.1f} | {out['nbytes'] / 2**20:.1f} |")
    print(f"mean and std: largest difference {rel:.1e} of the std; min/max identical: {exact}")
    print(f"quantiles 5/50/95 %: worst rank error {worst:.2e} (proven bound reached {s['bound']:.2e}, "
          f"a priori {Quantiles.error_bound(a.runs, a.k):.2e})")


if __name__ == "__main__":
    main()

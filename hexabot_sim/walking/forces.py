"""Foot forces of a walk as figures of merit: bounces, touchdown impacts, stance ripple, load sharing (issue 19).

Every function takes the feet's normal forces as an array (n, n_legs) [N] sampled every `dt` [s] and works on
any trace, so each metric is tested on synthetic force traces whose answers are known by construction.
"""

from __future__ import annotations

import math

import numpy as np

from hexabot_sim.result import Metric

BOUNCE_TIME: float = 0.060  # [s] a loaded foot that unloads for less than this and lands again bounced
IMPACT_TIME: float = 0.050  # [s] the touchdown impact is the peak force over this first part of a stance
RIPPLE_WINDOW: float = 0.025  # [s] the stance force's ripple is what differs from its moving mean over this


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs [start, end) of True in a 1-d boolean array."""
    padded = np.concatenate([[False], flags, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def gaps(loaded: np.ndarray, dt: float) -> list[tuple[int, int]]:
    """Short unloaded gaps [start, end) of one foot (n,): loaded before and after, under BOUNCE_TIME long."""
    out = []
    for start, end in _runs(~loaded):
        if start > 0 and end < len(loaded) and (end - start) * dt < BOUNCE_TIME - 1e-12:
            out.append((start, end))
    return out


def bounces(loaded: np.ndarray, dt: float) -> int:
    """Times a loaded foot (n,) unloaded for less than BOUNCE_TIME and landed again."""
    return len(gaps(loaded, dt))


def stances(loaded: np.ndarray, dt: float, whole: bool = True) -> list[tuple[int, int]]:
    """Stances [start, end) of one foot (n,): its loaded runs with the bounces bridged; `whole`: only those that
    begin and end inside the trace (a run at the trace's edge has no touchdown or lift-off in it)."""
    bridged = loaded.copy()
    for start, end in gaps(loaded, dt):
        bridged[start:end] = True
    return [(s, e) for s, e in _runs(bridged) if not whole or (s > 0 and e < len(loaded))]


def impact_ratios(force: np.ndarray, loaded: np.ndarray, dt: float) -> np.ndarray:
    """Per stance of one foot: the peak force over its first IMPACT_TIME over its mean force (k,)."""
    first = max(1, round(IMPACT_TIME / dt))
    ratios = [force[s : min(e, s + first)].max() / force[s:e].mean() for s, e in stances(loaded, dt)]
    return np.array([r for r in ratios if np.isfinite(r)])


def ripple(force: np.ndarray, loaded: np.ndarray, dt: float) -> float:
    """RMS [N] of one foot's force (n,) minus its centred RIPPLE_WINDOW moving mean, over its loaded rows whose
    window lies inside their stance (the touchdown's and lift-off's steps are not ripple; a bounce inside a stance
    is); 0 where there are none."""
    half = round(RIPPLE_WINDOW / dt) // 2
    squares, count = 0.0, 0
    for s, e in stances(loaded, dt, whole=False):
        if e - s <= 2 * half:
            continue
        cum = np.concatenate([[0.0], np.cumsum(force[s:e])])
        inner = np.arange(half, e - s - half)  # rows of the stance with the whole window inside it
        mean = (cum[inner + half + 1] - cum[inner - half]) / (2 * half + 1)
        residual = (force[s:e][inner] - mean)[loaded[s:e][inner]]
        squares += float(np.sum(residual**2))
        count += residual.size
    return math.sqrt(squares / count) if count else 0.0


def load_shares(force: np.ndarray, loaded: np.ndarray, planned: np.ndarray) -> np.ndarray:
    """Per foot (n_legs,): its mean share of the load carried by the feet the plan has down, relative to an equal
    share (1: equal), over the rows where it and every other foot the plan has down carry load (NaN: none).

    share_i = F_i / (sum of F_j over the planned stance feet j / their number).
    """
    n_down = planned.sum(axis=1)  # (n,)
    total = np.where(planned, force, 0.0).sum(axis=1)  # (n,)
    together = (planned <= loaded).all(axis=1) & (n_down > 0) & (total > 0)  # every planned foot loaded
    out = np.full(force.shape[1], np.nan)
    for i in range(force.shape[1]):
        rows = together & planned[:, i]
        if rows.any():
            out[i] = float(np.mean(force[rows, i] * n_down[rows] / total[rows]))
    return out


def force_metrics(
    force: np.ndarray,
    loaded: np.ndarray,
    planned: np.ndarray,
    dt: float,
    weight: float,
    legs: tuple[str, ...],
) -> dict[str, Metric]:
    """The foot-force metrics of a walk (over the rows given: the steady walk), per walk and per foot `<name>_<leg>`.

    Args:
        force: Normal force of each foot (n, n_legs) [N].
        loaded: The feet that carry load (n, n_legs) (above walking.constants.LOADED_FRACTION of a foot's share).
        planned: The feet the gait plan has in stance (n, n_legs).
        dt: Time between rows [s].
        weight: The robot's weight [N]; a foot's static share is weight / n_legs.
        legs: The legs' names, in the columns' order.
    """
    share = weight / len(legs)
    # A stance counts for the impact only if it starts and ends inside the rows (a one-cycle window of the tripod
    # holds none: its stances start and end on the window's edges).
    no_stance = "no stance started and ended inside the steady walk's window; a longer walk has some"
    n_bounces = [bounces(loaded[:, i], dt) for i in range(len(legs))]
    impacts = [impact_ratios(force[:, i], loaded[:, i], dt) for i in range(len(legs))]
    impact = [float(r.max()) if r.size else None for r in impacts]
    ripples = [ripple(force[:, i], loaded[:, i], dt) / share for i in range(len(legs))]
    shares = load_shares(force, loaded, planned)
    bearing = (loaded & planned).sum(axis=0)
    stance_rows = planned.sum(axis=0)
    # NaN (None in the metrics) for a foot the plan never has down in these rows (a short walk's window at a long
    # period): it read 0, as if the foot had never carried load.
    fraction = np.where(stance_rows > 0, bearing / np.maximum(stance_rows, 1), np.nan)
    all_impacts = np.concatenate(impacts)
    loaded_any = loaded.any(axis=0)
    # The walk's ripple: the RMS over every foot's loaded rows, each foot weighted by its loaded time.
    pooled = np.sqrt(sum(r * r * loaded[:, i].sum() for i, r in enumerate(ripples)) / max(loaded.sum(), 1))
    out = {
        "foot_bounces": Metric(
            int(sum(n_bounces)),
            "1",
            f"a loaded foot unloading for under {BOUNCE_TIME * 1000:g} ms and landing again, all feet (steady walk)",
        ),
        "touchdown_impact_ratio": Metric(
            float(all_impacts.max()) if all_impacts.size else None,
            "1",
            f"peak force in the first {IMPACT_TIME * 1000:g} ms of a stance over that stance's mean, the worst stance"
            + ("" if all_impacts.size else f"; null here: {no_stance}"),
        ),
        "touchdown_impact_ratio_mean": Metric(
            float(all_impacts.mean()) if all_impacts.size else None,
            "1",
            "touchdown_impact_ratio, mean over stances" + ("" if all_impacts.size else f"; null here: {no_stance}"),
        ),
        "stance_force_ripple": Metric(
            float(pooled),
            "1",
            f"RMS of a loaded foot's force minus its {RIPPLE_WINDOW * 1000:g} ms moving mean, over a foot's static "
            "share (weight / legs), all feet",
        ),
        "load_share_min": Metric(
            float(np.nanmin(shares)) if np.isfinite(shares).any() else None,
            "1",
            "smallest mean share of the load a stance foot carries while every planned stance foot is down "
            "(1: an equal share)",
        ),
        "stance_loaded_fraction": Metric(
            float(bearing.sum() / stance_rows.sum()) if stance_rows.sum() else None,
            "1",
            "share of the planned stance time in which the feet carry load, all feet",
        ),
        "stance_loaded_fraction_min": Metric(
            float(np.nanmin(fraction)) if np.isfinite(fraction).any() else None,
            "1",
            "stance_loaded_fraction of the foot that carries load least often",
        ),
    }
    for i, leg in enumerate(legs):
        out |= {
            f"foot_bounces_{leg}": Metric(n_bounces[i], "1", f"foot_bounces of foot {leg}"),
            f"touchdown_impact_ratio_{leg}": Metric(
                impact[i],
                "1",
                f"touchdown_impact_ratio of foot {leg}" + ("" if impacts[i].size else f"; null here: {no_stance}"),
            ),
            f"stance_force_ripple_{leg}": Metric(
                ripples[i] if loaded_any[i] else None, "1", f"stance_force_ripple of foot {leg}"
            ),
            f"load_share_{leg}": Metric(
                float(shares[i]) if np.isfinite(shares[i]) else None, "1", f"mean load share of foot {leg}"
            ),
            f"stance_loaded_fraction_{leg}": Metric(
                float(fraction[i]) if np.isfinite(fraction[i]) else None, "1", f"stance_loaded_fraction of foot {leg}"
            ),
        }
    return out

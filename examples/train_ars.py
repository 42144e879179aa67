"""Augmented Random Search (Mania, Guy, Recht 2018) on HexabotCommand-v0: a linear policy, no deep learning.

ARS V2-t: the policy is a = clip(M [(s - mu) / sigma, 1], -1, 1), mu and sigma the running mean and standard
deviation of the states seen (sigma at least SIGMA_FLOOR: near-constant inputs are not blown up into noise), the
constant 1 a bias (the commanded twist has a mean the normalisation removes). Each iteration draws N directions
delta_i (Gaussian, M's shape), runs an episode at M + nu delta_i and one at M - nu delta_i (the same seed for both:
common random numbers), keeps the b directions whose better return is highest and steps M by
alpha / (b sigma_R) sum (r+ - r-) delta_i, sigma_R the standard deviation of those 2b returns. Rollouts run on a
process pool (one environment per worker).

    python examples/train_ars.py [--iterations 30] [--workers 2] [--plot c.png] [--save p.npz] [--video a.mp4]
                                 [--watch]

Before and after training it reports the mean return of the policy over the same evaluation seeds (episodes of
--horizon steps of 0.1 s, commands drawn per episode by the environment).
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

ENV_ID = "hexabot_sim/HexabotCommand-v0"
_ENV = None  # each worker's environment
SIGMA_FLOOR: float = 0.01  # the smallest standard deviation a state's input is divided by


def _worker_env():
    global _ENV
    if _ENV is None:
        import gymnasium

        import hexabot_sim.envs  # noqa: F401 (registers the ids)

        _ENV = gymnasium.make(ENV_ID).unwrapped
    return _ENV


def rollout(args) -> tuple[float, np.ndarray, np.ndarray, int]:
    """(return, sum of states, sum of squared states, steps) of one episode of the policy M with normalisation."""
    weights, mu, sigma, seed, horizon = args
    env = _worker_env()
    obs, _ = env.reset(seed=int(seed))
    total, n = 0.0, 0
    s1, s2 = np.zeros_like(obs), np.zeros_like(obs)
    for _ in range(horizon):
        s1 += obs
        s2 += obs * obs
        n += 1
        action = np.clip(weights[:, :-1] @ ((obs - mu) / sigma) + weights[:, -1], -1.0, 1.0)
        obs, reward, terminated, truncated, _ = env.step(action)
        total += reward
        if terminated or truncated:
            break
    return total, s1, s2, n


class RunningStats:
    """Mean and standard deviation of the states seen (ARS V2's state normalisation)."""

    def __init__(self, size: int) -> None:
        self.n, self.s1, self.s2 = 0, np.zeros(size), np.zeros(size)

    def add(self, s1: np.ndarray, s2: np.ndarray, n: int) -> None:
        self.n, self.s1, self.s2 = self.n + n, self.s1 + s1, self.s2 + s2

    def mean_std(self) -> tuple[np.ndarray, np.ndarray]:
        if self.n < 2:
            return np.zeros_like(self.s1), np.ones_like(self.s1)
        mean = self.s1 / self.n
        var = np.maximum(self.s2 / self.n - mean * mean, 0.0)
        return mean, np.maximum(np.sqrt(var), SIGMA_FLOOR)


def evaluate(pool, weights, mu, sigma, seeds, horizon) -> np.ndarray:
    return np.array([r[0] for r in pool.map(rollout, [(weights, mu, sigma, s, horizon) for s in seeds])])


def play(env, weights, mu, sigma, seed: int, horizon: int, frame=None) -> None:
    """One episode of the policy in `env`; `frame(env)` after the reset and after every step."""
    obs, _ = env.reset(seed=seed)
    if frame:
        frame(env)
    for _ in range(horizon):
        obs, _, terminated, _, _ = env.step(np.clip(weights[:, :-1] @ ((obs - mu) / sigma) + weights[:, -1], -1, 1))
        if frame:
            frame(env)
        if terminated:
            break


def write_video(path: str, weights, mu, sigma, seed: int, horizon: int) -> None:
    """One episode of the policy, a frame per action (the environment's render_fps), encoded by imageio-ffmpeg."""
    import gymnasium
    import imageio.v2 as imageio

    env = gymnasium.make(ENV_ID, render_mode="rgb_array").unwrapped
    with imageio.get_writer(path, fps=env.metadata["render_fps"], macro_block_size=2) as writer:
        play(env, weights, mu, sigma, seed, horizon, lambda e: writer.append_data(e.render()))
    env.close()


def watch_window():
    """The environment with a window on the display (render_mode="human"), or exit in one line if none can open:
    asked before the training, not after it."""
    import gymnasium

    try:
        return gymnasium.make(ENV_ID, render_mode="human").unwrapped
    except (RuntimeError, gymnasium.error.DependencyNotInstalled) as e:
        raise SystemExit(f"train_ars.py: --watch: {e}") from None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--iterations", type=int, default=30, help="at least 1")
    parser.add_argument("--directions", type=int, default=16, help="N: directions per iteration")
    parser.add_argument("--top", type=int, default=8, help="b: best directions used in the update")
    parser.add_argument("--step-size", type=float, default=0.02, help="alpha")
    parser.add_argument("--noise", type=float, default=0.02, help="nu: exploration noise")
    parser.add_argument("--horizon", type=int, default=30, help="steps of 0.1 s per episode (3 s)")
    parser.add_argument("--eval-episodes", type=int, default=8)
    parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--plot", help="write the learning curve to this PNG")
    parser.add_argument("--save", help="write the policy (weights, mu, sigma) to this .npz")
    parser.add_argument("--video", help="write an MP4 of the learned policy's first evaluation episode")
    parser.add_argument("--watch", action="store_true", help="then show that episode in a window (needs a display)")
    args = parser.parse_args()
    if args.iterations < 1:
        parser.error(f"--iterations must be at least 1; got {args.iterations}")
    window = watch_window() if args.watch else None

    env = _worker_env()
    n_obs, n_act = env.observation_space.shape[0], env.action_space.shape[0]
    rng = np.random.default_rng(args.seed)
    weights = np.zeros((n_act, n_obs + 1))  # the zero policy: mid-range action (no twist, mid step height)
    stats = RunningStats(n_obs)
    eval_seeds = 10_000 + np.arange(args.eval_episodes)  # never trained on
    curve: list[tuple[float, float]] = []  # (wall seconds, mean evaluation return)
    started = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        before = evaluate(pool, weights, *stats.mean_std(), eval_seeds, args.horizon)
        curve.append((0.0, float(before.mean())))
        print(f"before: return {before.mean():.1f} +- {before.std():.1f} over {len(before)} episodes", flush=True)
        for it in range(args.iterations):
            mu, sigma = stats.mean_std()
            deltas = rng.standard_normal((args.directions, *weights.shape))
            seeds = rng.integers(0, 2**31, args.directions)
            jobs = [(weights + sign * args.noise * d, mu, sigma, s, args.horizon)
                    for d, s in zip(deltas, seeds, strict=True) for sign in (1.0, -1.0)]  # fmt: skip
            results = list(pool.map(rollout, jobs))
            for _, s1, s2, n in results:
                stats.add(s1, s2, n)
            returns = np.array([r[0] for r in results]).reshape(args.directions, 2)  # (N, +/-)
            best = np.argsort(returns.max(axis=1))[::-1][: args.top]
            spread = returns[best].std() or 1.0
            step = np.tensordot(returns[best, 0] - returns[best, 1], deltas[best], axes=1)
            weights = weights + args.step_size / (args.top * spread) * step
            score = evaluate(pool, weights, *stats.mean_std(), eval_seeds, args.horizon)
            curve.append((time.perf_counter() - started, float(score.mean())))
            print(f"iteration {it + 1:3d}: evaluation return {score.mean():7.1f} +- {score.std():5.1f} "
                  f"({curve[-1][0]:.0f} s)", flush=True)  # fmt: skip
    better = int((score > before).sum())  # the same evaluation seeds (commands, start noise) before and after
    print(f"after {args.iterations} iterations ({curve[-1][0]:.0f} s on {args.workers} workers): return "
          f"{score.mean():.1f} +- {score.std():.1f} (before {before.mean():.1f}); higher in {better} of "
          f"{len(score)} evaluation episodes, by {np.mean(score - before):+.1f} on average")  # fmt: skip
    mu, sigma = stats.mean_std()
    if args.save:
        np.savez(args.save, weights=weights, mu=mu, sigma=sigma)
        print(f"policy: {args.save}")
    if args.video:
        write_video(args.video, weights, mu, sigma, int(eval_seeds[0]), args.horizon)
        print(f"video: {args.video}")
    if args.plot:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6, 3.5), layout="constrained")
        ax = fig.add_subplot()
        t, r = zip(*curve, strict=True)
        ax.plot(t, r, marker="o")
        ax.set(xlabel="wall time [s]", ylabel=f"mean return ({args.eval_episodes} episodes of {args.horizon} steps)",
               title=f"ARS on {ENV_ID}")  # fmt: skip
        ax.grid(alpha=0.3)
        fig.savefig(args.plot, dpi=110)
        print(f"learning curve: {args.plot}")
    if window is not None:
        print("watching the first evaluation episode in a window", flush=True)
        hold = round(1.0 / window.dt)  # the start held for a second: a window's first frame takes ~1 s on software GL

        def held(env) -> None:
            nonlocal hold
            while hold > 0:
                hold -= 1
                env.render()

        play(window, weights, mu, sigma, int(eval_seeds[0]), args.horizon, held)
        window.close()


if __name__ == "__main__":
    main()

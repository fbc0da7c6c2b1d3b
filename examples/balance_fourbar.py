"""Shaking-force balancing of the bundled four-bar (run after ``pip install ".[plot]"``).

1. Drive the crank of the bundled crank-rocker four-bar at its scene speed (30 rad/s) over one
   revolution and report the shaking force and moment, the driving torque and the bearing
   forces.
2. Balance the shaking force completely with one counterweight on the crank and one on the
   rocker (Berkof–Lowen): rings of candidate point masses about each ground pivot, and the
   shaking force required to vanish at every instant. The masses found are checked against
   Berkof and Lowen's closed form.
3. Trade the shaking moment against the shaking force: a compromise balance and the Pareto
   front between the two.

Writes balance_fourbar_unbalanced.png, balance_fourbar.png, balance_fourbar_tradeoff.png and
balance_fourbar_pareto.png to the directory given as the first argument (default: the current
one). The same from the command line:

    pointmass-dyn balance fourbar --counterweight crank:0.02 --counterweight rocker:0.02 \
        --zero force --plot balance_fourbar.png
"""

from __future__ import annotations

import sys
from pathlib import Path

import pointmass_dyn as pmd
from pointmass_dyn.plotting import objective_rms, plot_balance, plot_motion, plot_pareto

out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(".")
out_dir.mkdir(parents=True, exist_ok=True)

# 1. The mechanism along a driven revolution -------------------------------------------------
scene = pmd.load_scene("fourbar")
model = scene.model
gravity = next(e.g for e in scene.effects if e.g is not None)
motion = pmd.prescribed_motion(model, "crank", speed=30.0, samples=360, q_guess=scene.q0,
                               gravity=gravity)
print("Four-bar driven at 30 rad/s, unbalanced (RMS and peak over a revolution):")
for name, v in motion.summary().items():
    print(f"  {name:<30} RMS {v['rms']:10.4g}   peak {v['peak']:10.4g}")
plot_motion(motion, out_dir / "balance_fourbar_unbalanced.png", title="fourbar, unbalanced")

# 2. Complete force balance: counterweights on crank and rocker ------------------------------
radius = 0.02  # m from each ground pivot
rings = [
    pmd.Counterweight.ring("crank", [0, 0, 0], radius, count=24),
    pmd.Counterweight.ring("rocker", [0, 0, 0], radius, count=24),
]
force_balanced = pmd.balance(motion, counterweights=rings, zero=("force",))
print("\nComplete shaking-force balance (counterweights on crank and rocker):")
print(force_balanced.table())
for body, position, mass in force_balanced.counterweights:
    print(f"  counterweight on {body}: {1e3 * mass:.3f} g at "
          f"({1e3 * position[0]:.2f}, {1e3 * position[1]:.2f}) mm in its frame")

# Berkof–Lowen: the total centre of mass stays put when
#   m_crank r_crank = m_coupler L_crank (r_coupler / L_coupler − 1)   (along the crank)
#   m_rocker r_rocker = −m_coupler r_coupler L_rocker / L_coupler      (along the rocker)
# (first moments about each ground pivot, along the link's own axis, coupler COM on its line).
l_crank, l_coupler, l_rocker = 0.035, 0.09, 0.07
coupler = model.body("coupler")
r_coupler = coupler.com[0]
need_crank = coupler.mass * l_crank * (r_coupler / l_coupler - 1.0)
need_rocker = -coupler.mass * r_coupler * l_rocker / l_coupler
for body, need in (("crank", need_crank), ("rocker", need_rocker)):
    new = force_balanced.bodies[body]
    got = new.mass * new.com[0]
    print(f"  {body}: first moment {got:.6e} kg·m, Berkof–Lowen {need:.6e} kg·m "
          f"(difference {abs(got - need):.1e})")
    assert abs(got - need) <= 1e-9 * abs(need)
plot_balance(force_balanced, out_dir / "balance_fourbar.png",
             title="fourbar at 30 rad/s: complete shaking-force balance (Berkof–Lowen)")

# 3. Trading the shaking moment --------------------------------------------------------------
# Force balance raises the shaking moment (the counterweights add inertia); weighing both
# RMS values (each relative to its unbalanced value) lands in between.
tradeoff = pmd.balance(motion, counterweights=rings, objective={"force": 1.0, "moment": 1.0})
print("\nForce and moment weighed equally:")
print(tradeoff.table())
plot_balance(tradeoff, out_dir / "balance_fourbar_tradeoff.png",
             title="fourbar at 30 rad/s: shaking force and moment weighed equally")

front = pmd.pareto_front(motion, ("force", "moment"), count=9, counterweights=rings)
print("\nPareto front (RMS shaking force in N, RMS shaking moment in N·m, mass added in g):")
print(f"  unbalanced       {objective_rms(motion, 'force'):10.4g} "
      f"{objective_rms(motion, 'moment'):10.4g}")
for b in front:
    w = b.objective["moment"] / sum(b.objective.values())
    added = 1e3 * (b.model.total_mass - model.total_mass)
    print(f"  w_moment = {w:4.2f}  {objective_rms(b.after, 'force'):10.4g} "
          f"{objective_rms(b.after, 'moment'):10.4g} {added:8.2f}")
plot_pareto(front, ("force", "moment"), out_dir / "balance_fourbar_pareto.png",
            title="fourbar: RMS shaking force against moment")
print(f"\nplots written to {out_dir.resolve()}")

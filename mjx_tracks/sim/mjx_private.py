"""Every use of MJX's private API (`mujoco.mjx._src`, `Data._impl`) lives here, and only here.

The track model needs to act between collision and the constraint solver, which MJX's public
`mjx.step` does not allow, so `step` below runs `mjx.step`'s stages itself (mujoco-mjx 3.17.0),
its last stage `solve`: MJX's Newton solver with its iterations in a loop of fixed length.
`check_model` asserts, when a model is compiled, the assumptions that makes: the implicitfast
integrator (the step ends with `forward.implicit`), no sensors (sensor stages are skipped),
pyramidal cones and condim 3 on every colliding geom (4 friction rows per contact), the Newton solver.
tests/test_mjx_private.py checks that `step` with no-op hooks equals `mjx.step` bit for bit, and
`solve` MJX's `solver.solve`, so an MJX upgrade that changes these stages fails there, not silently
in the physics.
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp
import mujoco
from mujoco import mjx
from mujoco.mjx._src import collision_driver, constraint, forward, smooth, solver
from mujoco.mjx._src import math as mjx_math

ContactHook = Callable[[mjx.Model, mjx.Data], tuple[mjx.Data, Any]]
ArefHook = Callable[[mjx.Model, mjx.Data, Any], jax.Array]


def check_model(m: mujoco.MjModel) -> None:
  """Raises ValueError if the model breaks an assumption of `step`."""
  if m.opt.integrator != mujoco.mjtIntegrator.mjINT_IMPLICITFAST:
    raise ValueError("the track model's step needs integrator='implicitfast'")
  if m.nsensor:
    raise ValueError(f"the track model's step skips sensor stages; the model has {m.nsensor} sensors")
  if m.opt.cone != mujoco.mjtCone.mjCONE_PYRAMIDAL:
    raise ValueError("the track model needs cone='pyramidal' (4 friction rows per contact)")
  colliding = (m.geom_contype | m.geom_conaffinity) != 0
  if (m.geom_condim[colliding] != 3).any():
    raise ValueError("the track model expects condim 3 on every colliding geom")
  if m.opt.solver != mujoco.mjtSolver.mjSOL_NEWTON:
    raise ValueError("the track model's step runs MJX's Newton solver (solver='Newton')")


def step(m: mjx.Model, d: mjx.Data, on_contacts: ContactHook, aref_shift: ArefHook) -> mjx.Data:
  """mjx.step's stages; on_contacts edits the contacts after collision and returns auxiliary data,
  aref_shift(m, d, aux) is added to the constraint rows' reference acceleration before solving."""
  for stage in (smooth.kinematics, smooth.com_pos, smooth.camlight, smooth.tendon, smooth.crb,
                smooth.tendon_armature, smooth.factor_m, collision_driver.collision):
    d = stage(m, d)
  d, aux = on_contacts(m, d)
  d = constraint.make_constraint(m, d)
  d = d.tree_replace({"_impl.efc_aref": d._impl.efc_aref + aref_shift(m, d, aux)})
  for stage in (smooth.transmission, forward.fwd_velocity, forward.fwd_actuation,
                forward.fwd_acceleration, solve):
    d = stage(m, d)
  return forward.implicit(m, d)


def solve(m: mjx.Model, d: mjx.Data) -> mjx.Data:
  """`solver.solve` (Newton) with the same figures (bit for bit on the CPU: tests/test_mjx_private.py),
  its iterations a loop of m.opt.iterations passes that leave the solver's context as it is once it
  has converged, where MJX runs a while loop that stops there. A GPU runs a loop of known length
  without reading its condition back to the host after every pass (the paper study's SAC program
  1.17x: docs/benchmarks.md); MJX's while loop, batched by vmap, runs until every robot has
  converged, with the converged ones' contexts kept as they are, as here."""
  d = d.replace(qacc=_warmstart(m, d))
  ctx = solver.Context.create(m, d)
  if m.opt.iterations == 1:  # as MJX: one pass, whatever the convergence
    ctx = _newton_pass(m, d, ctx)
  else:
    def one(ctx, _):
      improvement = solver._rescale(m, d, ctx.prev_cost - ctx.cost)
      gradient = solver._rescale(m, d, mjx_math.norm(ctx.grad))
      # MJX's condition (its pass count below m.opt.iterations: the loop's length)
      go = (improvement >= m.opt.tolerance) & (gradient >= m.opt.tolerance)
      passed = _newton_pass(m, d, ctx)
      return jax.tree.map(lambda new, old: jnp.where(go, new, old), passed, ctx), None
    ctx = jax.lax.scan(one, ctx, None, length=m.opt.iterations)[0]
  return d.tree_replace({"qfrc_constraint": ctx.qfrc_constraint, "qacc": ctx.qacc,
                         "_impl.efc_force": ctx.efc_force})


def _warmstart(m: mjx.Model, d: mjx.Data) -> jax.Array:
  """solver.solve's first acceleration: the last step's where its constraint cost is lower than the
  unconstrained one's."""
  if m.opt.disableflags & mjx.DisableBit.WARMSTART:
    return d.qacc_smooth
  warm = solver.Context.create(m, d.replace(qacc=d.qacc_warmstart), grad=False)
  smooth_ = solver.Context.create(m, d.replace(qacc=d.qacc_smooth), grad=False)
  return jnp.where(warm.cost < smooth_.cost, d.qacc_warmstart, d.qacc_smooth)


def _newton_pass(m: mjx.Model, d: mjx.Data, ctx: solver.Context) -> solver.Context:
  """One of solver.solve's Newton iterations: a line search along the search direction, then the
  constraint forces, cost and gradient at the new acceleration and the next direction."""
  ctx = solver._linesearch(m, d, ctx)
  ctx = solver._update_constraint(m, d, ctx)
  ctx = solver._update_gradient(m, d, ctx)
  return ctx.replace(search=-ctx.Mgrad, solver_niter=ctx.solver_niter + 1)


def contacts(d: mjx.Data):
  """The contact struct (pos, frame, friction, dist, geom, solref, ...) of a step."""
  return d._impl.contact


def with_contacts(d: mjx.Data, contact) -> mjx.Data:
  return d.tree_replace({"_impl.contact": contact})


def efc_rows(d: mjx.Data) -> int:
  """Number of constraint rows (per robot, for a batch too)."""
  return d._impl.efc_aref.shape[-1]


def contact_row0(m: mujoco.MjModel) -> int:
  """First constraint row of the contacts (after equality, friction and limit rows)."""
  ne, nf, nl, _ = constraint.counts(constraint.make_efc_type(m))
  return int(ne + nf + nl)


def contact_damping(m: mjx.Model, solref: jax.Array, solimp: jax.Array, pos: jax.Array) -> jax.Array:
  """Per contact: the damping b of its constraint rows (aref = -b J qvel - k imp pos)."""
  _, b, _ = jax.vmap(lambda sr, si, p: constraint._kbi(m, sr, si, p))(solref, solimp, pos)
  return b


@jax.jit
def kinematics(m: mjx.Model, d: mjx.Data) -> mjx.Data:
  """Body / geom / site poses and centres of mass consistent with qpos (jitted: traced once per
  model and process, as simulator.step_with_tracks)."""
  return smooth.com_pos(m, smooth.kinematics(m, d))

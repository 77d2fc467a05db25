"""One engine: every model — single mode, Galerkin, field and the 3D rod — runs through the one
`jaxrod.simulate` (one scheme, one loop, one `Solution`), under `jit` and `vmap`."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.scene import Scene

ROD = jr.RodChannel.reference(0.3)
# the 3D rod's case (40 s of compilation) is `slow`: test_sweep's 3D test checks members against
# single runs of the same engine in the default suite
KINDS = [("mode", None, 0.2), ("galerkin", 8, 0.2), ("field", 24, 0.2),
         pytest.param("rod3d", 10, 0.03, marks=pytest.mark.slow)]


# the energy balance's largest drift over the largest energy, at 10× what was measured for the
# stable and the buckled run: single mode 6.6e-6 / 4.0e-5, Galerkin 8.9e-5 / 3.9e-3, field
# 2.0e-4 / 3.6e-3 (the 3D rod's slow case keeps 5 %)
BALANCE = {"mode": 4e-4, "galerkin": 0.04, "field": 0.036, "rod3d": 0.05}


@pytest.mark.parametrize("kind,n,t1", KINDS)
def test_each_model_through_simulate_under_jit_and_vmap_equals_its_single_runs(kind, n, t1):
    dt = Scene(ROD, 5.0, kind=kind, n=n).step()
    amps = jnp.array([2e-3, 0.08])  # stable, buckled

    def scene(a):
        return Scene(ROD, 5.0, jr.SineVelocity(a, 6.0), kind, n=n, dt=dt)

    def run(a):
        s = scene(a)
        q0, v0 = s.initial_state()
        opts = jr.RunOptions(buckle_threshold=s.threshold)  # as `Scene.run`
        return jr.simulate(s.model(), s.integrator(), q0, v0, t1, n_save=21, options=opts, throw=False)

    batch = jax.jit(jax.vmap(run))(amps)
    assert batch.amplitude.shape == (2, 21)
    for i, a in enumerate(amps):
        one = scene(a).run(t1=t1, n_save=21)
        assert int(one.result) == 0 and bool(batch.buckled[i]) == bool(one.buckled)
        assert int(batch.n_steps[i]) == int(one.n_steps)
        # the 3D rod's friction pass computes in float32, and the batched compilation rounds
        # differently from the unbatched one (1.6e-7 measured; 1.2e-12 before the pass was float32):
        # within the pass's stated budget, 1e-5 of the amplitude (docs/rod3d.md, "Cost of a step").
        # The reduced models agree to 1e-12
        np.testing.assert_allclose(batch.amplitude[i], one.amplitude, rtol=1e-5 if kind == "rod3d" else 1e-12,
                                   atol=1e-300)
        np.testing.assert_allclose(batch.t_stop[i], one.t_stop, rtol=1e-12)
        # the energy balance closes for every model (E + dissipated − work_in constant)
        scale = max(float(jnp.max(jnp.abs(e))) for e in one.energies.values())
        assert float(jnp.max(jnp.abs(one.energy_balance))) < BALANCE[kind] * scale
    assert not bool(batch.buckled[0]) and bool(batch.buckled[1])


def test_options_have_one_meaning_for_every_model():
    """`stop_on_buckle=False` lets a buckled run go on (and still records the first crossing),
    for the per-DOF models alike (the 3D rod's E6 and helix runs use it: `slow` tests)."""
    for kind, n, t1 in (("field", 24, 0.2), ("galerkin", 8, 0.2)):
        s = Scene(ROD, 5.0, jr.SineVelocity(0.08, 6.0), kind, n=n)
        q0, v0 = s.initial_state()
        stop = jr.simulate(s.model(), s.integrator(), q0, v0, t1, n_save=11, throw=False,
                           options=jr.RunOptions(save_state=False))
        go_on = jr.simulate(s.model(), s.integrator(), q0, v0, t1, n_save=11, throw=False,
                            options=jr.RunOptions(save_state=False, stop_on_buckle=False))
        assert bool(stop.buckled) and bool(go_on.buckled), kind
        assert float(go_on.t_buckle) == float(stop.t_buckle), kind
        assert float(stop.t_stop) < t1 and float(go_on.t_stop) == pytest.approx(t1), kind
        assert int(go_on.n_steps) > int(stop.n_steps), kind


@pytest.mark.parametrize("early_exit", [True, False])
def test_a_run_with_a_progress_bar_equals_one_without(early_exit, capfd):
    """`RunOptions(progress=True)` reports each save interval to a tqdm bar on stderr (the
    bar counts to the save interval where the run stops) and changes nothing in the run."""
    s = Scene(ROD, 5.0, jr.SineVelocity(0.08, 6.0), "field", n=24)
    q0, v0 = s.initial_state()
    runs = [jr.simulate(s.model(), s.integrator(), q0, v0, 0.2, n_save=11, throw=False,
                        options=jr.RunOptions(save_state=False, early_exit=early_exit, progress=p))
            for p in (False, True)]
    err = capfd.readouterr().err
    np.testing.assert_array_equal(runs[0].amplitude, runs[1].amplitude)
    assert float(runs[0].t_buckle) == float(runs[1].t_buckle) and bool(runs[1].buckled)
    assert re.search(r"(^|\r)run: .*[ ?]save/s", err, re.M)  # the bar: "run", its saves, their rate
    # before its first compiled call a run says what it compiles, once per process and program
    compiling = "compiling FieldModel (24 nodes) with ProjectedVerlet"
    assert early_exit is False or compiling in err.splitlines()[0]
    jr.simulate(s.model(), s.integrator(), q0, v0, 0.2, n_save=11, throw=False,
                options=jr.RunOptions(save_state=False, early_exit=early_exit, progress=True))
    assert "compiling" not in capfd.readouterr().err


def test_the_later_saves_of_a_stopped_run_open_no_new_progress_bar(capfd):
    """The saves run in a loop of known length, so a run that stopped still reports its later
    save intervals (with `stopped` set): they draw nothing, and the next run gets its own bar."""
    from jaxrod.integrators import progress

    progress.tick(1, 10, False)
    progress.tick(2, 10, True)  # the run stops: its bar closes
    capfd.readouterr()
    for i in range(3, 11):
        progress.tick(i, 10, True)
    assert capfd.readouterr().err == "" and "bar" not in progress._BAR
    progress.tick(1, 10, False)  # a new run
    assert progress._BAR["bar"].n == 1
    progress.tick(10, 10, False)
    assert "bar" not in progress._BAR


def test_a_traced_smoothing_width_is_differentiable_through_simulate():
    """The step-limit check runs at trace time only when both the model and the scheme's
    parameters are concrete: with a friction smoothing width traced by `jit` (the failure
    atlas's gradient entry) it goes to the in-run check, and dA(T)/dȦ₀ by `jax.grad` matches
    central differences of the same function."""
    m = jr.SingleMode.from_rod(jr.RodChannel.reference(0.3), 6, dF=5.0)
    opts = jr.RunOptions(early_exit=False, save_state=False)

    def final(v0, eps):
        sol = jr.simulate(m, jr.ProjectedVerlet(1e-4, jr.Tanh(eps)), 0.0, v0, 0.05, n_save=2,
                          options=opts, throw=False)
        return sol.q_final

    eps = 2.0 * 1e-4 * float(m.f_d)  # h·f/ε = 0.5: the tanh law's gradient is sound there
    g = float(jax.jit(jax.grad(final))(0.004, eps))
    val = jax.jit(final)
    h = 1e-7
    fd = (float(val(0.004 + h, eps)) - float(val(0.004 - h, eps))) / (2 * h)
    assert np.isfinite(g) and g == pytest.approx(fd, rel=1e-5)


@pytest.mark.parametrize("kind,n", [("mode", None), ("field", 24)])
@pytest.mark.parametrize("bad", ["q", "v"])
@pytest.mark.parametrize("progress", [False, True])
def test_a_run_from_a_non_finite_state_reports_nonfinite(kind, n, bad, progress):
    """A NaN in the initial position or velocity is a failed run (`nonfinite`), with or without
    a progress bar, even where the friction pass would hold the rod at once (it sets a NaN
    velocity to zero, leaving a finite state that looked like a successful, stuck run)."""
    s = Scene(ROD, 5.0, jr.SineVelocity(2e-3, 6.0), kind, n=n)
    q0, v0 = s.initial_state()
    nan_first = lambda x: jnp.asarray(x).reshape(-1).at[0].set(jnp.nan).reshape(jnp.shape(x))
    q0 = nan_first(q0) if bad == "q" else q0
    v0 = nan_first(v0) if bad == "v" else v0
    sol = jr.simulate(s.model(), s.integrator(), q0, v0, 0.02, n_save=3, throw=False,
                      options=jr.RunOptions(progress=progress))
    assert int(sol.result) == jr.RESULTS.nonfinite
    assert not bool(sol.buckled)

"""Export of a 3D rod run: a ParaView time series (meshio) and an animated GIF (issue [ux])."""

import re

import numpy as np
import pytest

import jaxrod as jr
from jaxrod.rod3d import Rod3D, sine_velocity, step_limit

meshio = pytest.importorskip("meshio")


@pytest.mark.slow  # one 3D compilation (~15 s)
def test_vtk_series_reads_back_with_the_run_and_the_gif_has_every_frame(tmp_path):
    from PIL import Image

    from jaxrod.figures.export3d import animate, write_vtk

    rod = jr.RodChannel.reference(0.3)
    model = Rod3D(rod, 8, control="load", end_load=6.0)
    q0, v0 = model.initial_state(6.0, lateral_velocity=sine_velocity(model, 0.02))
    sol = jr.simulate(model, jr.ProjectedVerlet(0.5 * step_limit(model, q0)), q0, v0, 0.004, n_save=5,
                      options=jr.RunOptions(save_state=True, stop_when_stuck=False))
    paths = write_vtk(sol, model, str(tmp_path / "vtk"))
    assert len(paths) == 6 and paths[-1].endswith("rod.pvd")
    x = np.asarray(sol.q.x)
    for k, p in enumerate(paths[:-1]):
        m = meshio.read(p)
        assert m.points.shape == (9, 3)
        np.testing.assert_allclose(m.points, x[k], rtol=0, atol=1e-15)
        assert m.cells[0].type == "line" and len(m.cells[0].data) == 8
        np.testing.assert_allclose(m.point_data["theta"], np.asarray(sol.observables["theta"])[k])
        np.testing.assert_allclose(m.point_data["radius"], 0.5 * float(rod.d))
    times = [float(t) for t in re.findall(r'timestep="([^"]+)"', open(paths[-1]).read())]
    np.testing.assert_allclose(times, np.asarray(sol.ts))
    gif = animate(sol, model, str(tmp_path / "rod.gif"))
    assert Image.open(gif).n_frames == 5
    with pytest.raises(ValueError, match="kept no states"):
        write_vtk(jr.simulate(model, jr.ProjectedVerlet(0.5 * step_limit(model, q0)), q0, v0, 0.004, n_save=5,
                              options=jr.RunOptions(save_state=False, stop_when_stuck=False)), model, str(tmp_path))

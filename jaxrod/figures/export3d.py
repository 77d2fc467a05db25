"""Looking at a 3D rod run outside θ(s, t) maps: a ParaView time series and an animation.

- `write_vtk(sol, model, folder)`: one VTK polyline file per save (`rod_0000.vtu`, … via
  [meshio](https://github.com/nschloe/meshio): `pip install 'jaxrod[export]'`) with the node
  positions [m] and, per node, the rod's radius [m], θ [rad], the wall force per length [N/m]
  and the node velocity [m/s] where the run kept them, plus `rod.pvd`, the ParaView collection
  that orders the files by time [s]. Open `rod.pvd` in ParaView (a Tube filter on the radius
  shows the rod).
- `animate(sol, model, path)`: an animated GIF (matplotlib's Pillow writer) of the rod seen along
  the channel (cross-section, the wall drawn) and from above (θ against s).

Both need a run that kept its states (`RunOptions(save_state=True)`).
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["write_vtk", "animate"]


def _states(sol):
    if sol.q is None:
        raise ValueError("the run kept no states: simulate it with RunOptions(save_state=True).")
    x = np.asarray(sol.q.x)  # (T, n + 1, 3)
    return np.asarray(sol.ts), x


def write_vtk(sol, model, folder: str, every: int = 1) -> list[str]:
    """Write the run as a VTK time series under `folder` (created); every `every`-th save.

    **Returns:** the paths written, `rod.pvd` last."""
    try:
        import meshio
    except ImportError:
        raise ImportError("write_vtk needs meshio: pip install 'jaxrod[export]'") from None
    if not (isinstance(every, int) and every >= 1):
        raise ValueError(f"every = {every!r} is invalid: expected an int >= 1.")
    ts, x = _states(sol)
    os.makedirs(folder, exist_ok=True)
    n1 = x.shape[1]
    lines = [("line", np.stack([np.arange(n1 - 1), np.arange(1, n1)], -1))]
    radius = np.full(n1, 0.5 * float(model.rod.d))
    fields = {k: np.asarray(sol.observables[k]) for k in ("theta", "normal_force") if k in sol.observables}
    vel = np.asarray(sol.v.v) if sol.v is not None else None
    paths = []
    for k in range(0, len(ts), every):
        data = {"radius": radius, **{name: f[k] for name, f in fields.items()}}
        if vel is not None:
            data["velocity"] = vel[k]
        path = os.path.join(folder, f"rod_{k:04d}.vtu")
        meshio.write(path, meshio.Mesh(x[k], lines, point_data=data))
        paths.append(path)
    pvd = os.path.join(folder, "rod.pvd")
    with open(pvd, "w") as fh:
        fh.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n')
        for k, path in zip(range(0, len(ts), every), paths):
            fh.write(f'<DataSet timestep="{float(ts[k])!r}" file="{os.path.basename(path)}"/>\n')
        fh.write("</Collection>\n</VTKFile>\n")
    return paths + [pvd]


def animate(sol, model, path: str, fps: int = 20, every: int = 1) -> str:
    """An animated GIF at `path` of every `every`-th save, `fps` frames per second: left, the
    nodes seen along the channel axis inside the wall circle (lateral y and height z [mm]);
    right, θ [rad] against s [m]."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    from ..output import subplots

    ts, x = _states(sol)
    frames = list(range(0, len(ts), every))
    theta = np.arctan2(x[..., 1], -x[..., 2])
    s = np.linspace(0.0, float(model.rod.L), x.shape[1])
    Rw = (float(model.rod.R) + 0.5 * float(model.rod.d)) * 1e3
    fig, (ax0, ax1) = subplots(1, 2, figsize=(10, 4))
    a = np.linspace(0, 2 * np.pi, 200)
    ax0.plot(Rw * np.cos(a), Rw * np.sin(a), "k-", lw=0.8)
    ax0.set_aspect("equal")
    ax0.set_xlabel("y [mm]")
    ax0.set_ylabel("z [mm]")
    dots, = ax0.plot([], [], "o", ms=3)
    line, = ax1.plot([], [], "-")
    lim = max(float(np.max(np.abs(theta))), 1e-6) * 1.1
    ax1.set_xlim(0.0, s[-1])
    ax1.set_ylim(-lim, lim)
    ax1.set_xlabel("s [m]")
    ax1.set_ylabel("θ [rad]")
    title = ax1.set_title("")

    def draw(k):
        dots.set_data(x[k, :, 1] * 1e3, x[k, :, 2] * 1e3)
        line.set_data(s, theta[k])
        title.set_text(f"t = {ts[k] * 1e3:.2f} ms")
        return dots, line, title

    FuncAnimation(fig, draw, frames=frames, blit=False).save(path, writer=PillowWriter(fps=fps))
    return path

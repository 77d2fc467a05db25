"""The figure of `alternatives.py`: members/s against the batch size, one panel per n."""

from __future__ import annotations


def plot(rows, ns, path, info, steps):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    styles = {
        "jaxrod vmap (FD)": dict(color="C0", marker="o", lw=2),
        "jaxrod vmap (spectral, dense)": dict(color="C0", marker="s", ls="--"),
        "numpy vectorised (FD)": dict(color="C1", marker="^"),
        "python loop of jitted runs": dict(color="C2", ls=":"),
        "scipy solve_ivp RK45 (tanh law)": dict(color="C3", ls="-."),
        "scipy solve_ivp LSODA (tanh law)": dict(color="C4", ls="-."),
    }
    fig, axes = plt.subplots(1, len(ns), figsize=(5.2 * len(ns), 4.6), squeeze=False)
    for ax, n in zip(axes[0], ns):
        batches = sorted({r["batch"] for r in rows if r["n"] == n and r["impl"].startswith("jaxrod vmap")})
        for impl, st in styles.items():
            sel = [r for r in rows if r["impl"] == impl and r["n"] == n]
            if not sel:
                continue
            if impl.startswith(("jaxrod vmap", "numpy")):
                ax.plot([r["batch"] for r in sel], [r["members_per_s"] for r in sel], label=impl, **st)
            else:  # one member at a time: a constant rate
                ax.plot([batches[0], batches[-1]], [sel[-1]["members_per_s"]] * 2, label=impl, **st)
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("batch size (members per call)")
        ax.set_ylabel(f"members/s ({steps}-step horizon)")
        ax.set_title(f"n = {n}", fontsize=10)
        ax.grid(alpha=0.3, which="both")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"Field model throughput, float64, {info['device']}, {info['cores']} cores, "
                 f"JAX {info['jax']}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

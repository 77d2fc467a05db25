"""The reference paper's experiments, one module per experiment: `e2` (phase portraits), `e3`
(stability map), `e4` (critical load against μ), `e5` (buckling modes), `e6` (spectra; its full-
model part in `rod3d`), `rod3d` (E1 and the 3D rod's checks), `helix` (post-buckling). Each
experiment's function takes `(out, quick, progress)`, writes figures and CSV under `out` and
returns its numbers; `jaxrod reproduce` (`jaxrod.reproduce`) runs them and merges the numbers
into `results.json`."""

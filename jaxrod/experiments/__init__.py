"""The reference paper's experiments that need more than a sweep or a boundary search: the 3D
rod's E1, E6 and cross-checks (`jaxrod.experiments.rod3d`) and the post-buckling helix
(`jaxrod.experiments.helix`). `jaxrod reproduce` (`jaxrod.reproduce`) drives them with E2–E5."""

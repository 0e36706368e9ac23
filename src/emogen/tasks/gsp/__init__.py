"""The ``gsp`` task: Gibbs sampling with people (Harrison et al. 2020, NeurIPS) on the rig's
genes — chains of one face passed between participants, each moving one gene with a slider."""

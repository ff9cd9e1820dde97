"""Stage functions: one per Snakemake rule. They read inputs, call the physics, write outputs."""

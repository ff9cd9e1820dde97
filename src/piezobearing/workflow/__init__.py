"""What the Snakemake workflow needs of the package besides the stages: the registry of the config keys each
rule's stage reads and of the package code it runs."""

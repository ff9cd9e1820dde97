"""Stage functions: one per Snakemake rule. They read inputs, call the physics, write outputs."""

import logging


def log_progress() -> None:
    """Send the stages' progress and timing messages (logger ``piezobearing.*``) to stderr,
    which the rule's script has pointed at its log file."""
    if not logging.getLogger().handlers:
        logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")

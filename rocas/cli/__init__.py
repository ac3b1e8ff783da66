"""The command-line interface: one module per command (see rocas.cli.main)."""

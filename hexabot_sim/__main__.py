"""`python -m hexabot_sim`: the command line (hexabot_sim.cli)."""

from hexabot_sim.cli import build_parser, console, main

__all__ = ["build_parser", "console", "main"]

if __name__ == "__main__":
    console()

"""`python -m hexabot_sim`: the command line (hexabot_sim.cli), started as the console script starts it."""

if __name__ == "__main__":
    # Through _entry, as the `hexabot-sim` script: a Ctrl-C or SIGTERM while numpy and MuJoCo are still being
    # imported ends in one line (importing hexabot_sim.cli here first left them a traceback or a silent death).
    from hexabot_sim._entry import console

    console()
else:
    from hexabot_sim.cli import build_parser, console, main

    __all__ = ["build_parser", "console", "main"]

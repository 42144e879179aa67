"""The `hexabot-sim` console script: a Ctrl-C while the program is still loading ends quietly too."""

import os
import sys


def console() -> None:
    """Loads the command line (numpy, MuJoCo, ...) and runs it; Ctrl-C during the loading exits 130 in one line,
    SIGTERM and SIGHUP 143 and 129 (they killed the process without a word, as a signal death, not an exit code)."""
    import signal

    received: list[int] = []  # hexabot_sim.signals.RECEIVED_SIGNALS once imported (the handler comes first)

    def interrupted(signum: int, frame: object) -> None:
        received.append(signum)  # remembered even if an import swallows the exception
        raise KeyboardInterrupt

    try:  # from the first handler on: a stop request between two of these lines was a traceback
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            if signal.getsignal(sig) is not signal.SIG_IGN:
                signal.signal(sig, interrupted)
        from hexabot_sim import signals

        before, received = received, signals.RECEIVED_SIGNALS  # the handler appends there from now on
        received.extend(before)
        signals.quiet_interruptions()
        from hexabot_sim.cli import console as run

        if received:
            raise KeyboardInterrupt
    except BaseException as error:  # KeyboardInterrupt, or an ImportError a C extension wrapped it in
        cause: BaseException | None = error
        while cause is not None and not isinstance(cause, KeyboardInterrupt):
            cause = cause.__cause__ or cause.__context__
        if cause is None:
            raise
        signum = received[-1] if received else signal.SIGINT
        what = "interrupted" if signum == signal.SIGINT else f"stopped by {signal.Signals(signum).name}"
        try:
            sys.stderr.write(f"hexabot-sim: {what}; nothing written\n")
            sys.stderr.flush()
        except (OSError, ValueError):
            pass
        # Nothing is open yet, so no clean-up is lost: an exit that the interpreter cannot turn into a death by
        # SIGINT afterwards (it did, when a KeyboardInterrupt had passed through one of its own code runners during
        # the imports: SIGTERM then ended as -2, a shell's 130, about 1 run in 15 under load).
        os._exit(128 + signum)
    run()

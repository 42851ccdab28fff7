"""A script that runs ``klaw-ocp`` with every step slowed down, for tests that act on a real
process while it walks (interrupt it, remove its folder)."""
import textwrap


def slow_cli_script(pause_s: float) -> str:
    """The script's text: each step sleeps ``pause_s`` after it is solved; SIGINT gets Python's
    default handler back (a shell's background job would ignore it)."""
    return textwrap.dedent(f"""
        import signal, sys, time
        signal.signal(signal.SIGINT, signal.default_int_handler)
        from klaw_ocp.control.step import StepController
        original = StepController.solve_step
        def slow(self, *args, **kwargs):
            result = original(self, *args, **kwargs)
            time.sleep({pause_s!r})
            return result
        StepController.solve_step = slow
        from klaw_ocp.cli import main
        sys.exit(main(sys.argv[1:]))
    """)

"""The add-on's sigint_watch (operators/keyboard_interrupt.py, bpy-free): a Ctrl-C is seen even
when the KeyboardInterrupt it raises never reaches the polling loop.

Each case runs in a child Python, so that its signals and handlers cannot touch pytest's.
"""

import pathlib
import subprocess
import sys
import textwrap

ADDON = pathlib.Path(__file__).resolve().parents[2] / "addon"

PRELUDE = f"""
import gc, os, signal, sys, threading
sys.path.insert(0, {str(ADDON)!r})
from shgi_blender.operators.keyboard_interrupt import sigint_watch
"""


def run_child(body):
    """Runs PRELUDE + body in a child Python; returns its stdout (fails on a non-zero exit)."""
    code = PRELUDE + textwrap.dedent(body)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_a_sigint_swallowed_in_a_finaliser_is_still_seen():
    out = run_child("""
        class Finalised:
            def __del__(self):
                # The signal arrives as a finaliser runs: its KeyboardInterrupt is raised here,
                # and the interpreter only prints it ("Exception ignored in").
                os.kill(os.getpid(), signal.SIGINT)

        with sigint_watch() as interrupted:
            before = interrupted()
            cycle = Finalised()
            cycle.self = cycle
            del cycle
            try:
                gc.collect()
                for _ in range(1000):
                    pass
                escaped = False
            except KeyboardInterrupt:
                escaped = True
            print("escaped", escaped, "before", before, "seen", interrupted(),
                  "again", interrupted())
    """)
    assert "escaped False before False seen True again True" in out


def test_a_sigint_whose_handler_raises_nothing_is_still_seen():
    out = run_child("""
        signal.signal(signal.SIGINT, lambda *_: None)  # a handler that swallows it
        with sigint_watch() as interrupted:
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):
                pass
            print("seen", interrupted())
    """)
    assert "seen True" in out


def test_other_signals_do_not_count_and_the_previous_wakeup_fd_comes_back():
    out = run_child("""
        signal.signal(signal.SIGUSR1, lambda *_: None)
        read_fd, write_fd = os.pipe()
        os.set_blocking(write_fd, False)
        signal.set_wakeup_fd(write_fd)
        with sigint_watch() as interrupted:
            os.kill(os.getpid(), signal.SIGUSR1)
            for _ in range(1000):
                pass
            print("usr1 seen as sigint", interrupted())
        print("restored", signal.set_wakeup_fd(-1) == write_fd)
    """)
    assert "usr1 seen as sigint False" in out
    assert "restored True" in out


def test_outside_the_main_thread_it_never_fires():
    out = run_child("""
        result = []

        def worker():
            with sigint_watch() as interrupted:
                result.append(interrupted())

        thread = threading.Thread(target=worker)
        thread.start()
        thread.join()
        print("worker", result, "wakeup fd untouched", signal.set_wakeup_fd(-1) == -1)
    """)
    assert "worker [False] wakeup fd untouched True" in out

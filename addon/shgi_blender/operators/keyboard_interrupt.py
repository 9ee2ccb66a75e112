"""Ctrl-C (SIGINT) as KeyboardInterrupt while an operator waits for native work. No bpy.

An operator run from a script or in background mode (``blender -b``) waits on Blender's main
thread for its worker. Background Blender handles SIGINT itself: the first one only sets the
break flag renders read (creator_signals.c, "Sent an internal break event"), which Python cannot
read, and the second kills Blender. ``keyboard_interrupts()`` makes SIGINT raise
KeyboardInterrupt in the main thread for the duration of a ``with`` block, so the waiting
operator can cancel its worker and return CANCELLED, and then puts back the handler there was:
Python's own (Blender as a Python module), or Blender's C handler, saved and restored with
sigaction through ctypes because Python's ``signal.signal`` cannot reinstall a handler it did not
install. Where that is not possible (another thread, no sigaction), the block runs unchanged.

``sigint_watch()`` makes a Ctrl-C impossible to lose while the main thread polls a worker. A
SIGINT that Python handles raises KeyboardInterrupt in whatever Python code the main thread runs
next, and some code swallows it: a finaliser run by the garbage collector, or a callback Blender
calls and whose errors it only prints. Once swallowed, no exception reaches the polling loop,
which would wait for the worker to the end (a render of a million samples: for ever). The watch
lends Python's signal wake-up fd a pipe, which Python's C handler writes to as the signal
arrives, before any Python code runs; the loop reads it as it reads Blender's break flag.
"""

import ctypes
import ctypes.util
import os
import signal
import threading
from contextlib import contextmanager

# Bytes that hold a struct sigaction on every POSIX platform (152 on Linux x86-64, 16 on macOS);
# the struct is only saved and restored, never read.
SIGACTION_BYTES = 256


@contextmanager
def keyboard_interrupts():
    """While the block runs, SIGINT raises KeyboardInterrupt in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGINT)  # None: a handler installed outside Python
    saved = SavedDisposition.current()
    if previous is None and saved is None:  # a handler that could not be put back: keep it
        yield
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        # Python's table first (SIG_IGN for a handler it did not install: a Ctrl-C in between is
        # dropped, never fatal), then the exact disposition there was.
        signal.signal(signal.SIGINT, previous if previous is not None else signal.SIG_IGN)
        if saved is not None:
            saved.restore()


class SavedDisposition:
    """SIGINT's disposition as sigaction reports it, to be put back as it was."""

    def __init__(self, libc, action):
        self._libc = libc
        self._action = action

    @classmethod
    def current(cls):
        """The current disposition, or None where sigaction is not available."""
        try:
            libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
            sigaction = libc.sigaction
        except (OSError, AttributeError, TypeError):
            return None
        action = ctypes.create_string_buffer(SIGACTION_BYTES)
        if sigaction(signal.SIGINT, None, ctypes.byref(action)) != 0:
            return None
        return cls(libc, action)

    def restore(self):
        self._libc.sigaction(signal.SIGINT, ctypes.byref(self._action), None)


@contextmanager
def sigint_watch():
    """Yields a callable that is True once a SIGINT has arrived during the block (and stays
    True). It sees the signals Python handles (Blender as a Python module, or inside
    ``keyboard_interrupts()``); elsewhere (another thread, Blender's own handler) it stays False.
    The KeyboardInterrupt the signal raises is unchanged: the caller handles both."""
    read_fd, write_fd = os.pipe()
    try:
        os.set_blocking(read_fd, False)
        os.set_blocking(write_fd, False)
        try:
            previous = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
        except ValueError:  # not the main thread of the main interpreter
            yield lambda: False
            return
        seen = False

        def interrupted():
            nonlocal seen
            if not seen:
                try:
                    seen = signal.SIGINT in os.read(read_fd, 512)  # a byte per signal: its number
                except BlockingIOError:  # nothing arrived
                    pass
            return seen

        try:
            yield interrupted
        finally:
            signal.set_wakeup_fd(previous)  # an event loop's fd, or -1
    finally:
        os.close(read_fd)
        os.close(write_fd)

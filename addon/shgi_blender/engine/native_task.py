"""Native work on a worker thread, cancellable and polled from Blender's main thread. No bpy.

A NativeTask runs its subclass's ``_work()`` on a daemon thread. Every native call in it takes
the task's ``progress`` (a shgi.Progress) and releases the GIL, so the main thread stays
responsive and reads ``progress.fraction`` / ``progress.stage`` while it runs. ``cancel()``
makes the running call raise ``shgi.Cancelled`` within one chunk of work (< 0.2 s,
docs/architecture.md); the task then ends with ``cancelled`` set. Any other exception ends it with
``error`` set, for the main thread to report (a worker thread must not call bpy).

A ValueError (a native check's refusal) is kept with the panel setting named in place of the
native field (settings.name_settings), as the main thread reports it to the artist.

``wait`` and ``running`` read an Event the worker sets as it ends, not Thread.join: CPython
3.11's join, interrupted by a KeyboardInterrupt (Ctrl-C under the bpy module), releases the
lock the running thread holds and marks it stopped (threading.py, the bpo-45274 handler).
"""

import threading

from .. import settings


class NativeTask:
    """A worker thread running ``self._work()`` with a cancellable shgi.Progress.

    thread_name: the worker thread's name (it shows in debuggers and tracebacks).
    """

    def __init__(self, shgi, thread_name):
        self._shgi = shgi
        self.progress = shgi.Progress()
        self._thread = threading.Thread(target=self._run, name=thread_name, daemon=True)
        self._ended = threading.Event()
        self.error = None       # the exception that ended the task, other than Cancelled
        self.cancelled = False

    # --- main thread ---------------------------------------------------------------------------

    def start(self):
        try:
            self._thread.start()
        except BaseException:
            # A KeyboardInterrupt (Ctrl-C under the bpy module) can land in Thread.start() after
            # the worker began, while start() waits for it to run: the caller never gets the
            # task to cancel, so the work is cancelled here.
            self.progress.cancel()
            raise
        return self

    def cancel(self):
        """Asks the running native call to stop (it raises Cancelled within one chunk)."""
        self.progress.cancel()

    def wait(self, timeout=None):
        """Waits up to `timeout` seconds (None: until the end); True when the task has ended."""
        return self._ended.wait(timeout)

    @property
    def running(self):
        return self._thread.ident is not None and not self._ended.is_set()

    # --- worker thread -------------------------------------------------------------------------

    def _run(self):
        try:
            self._work()
        except self._shgi.Cancelled:
            self.cancelled = True
        except ValueError as error:  # a refusal, reported by the caller on the main thread
            self.error = ValueError(settings.name_settings(error))
        except Exception as error:  # reported by the caller on the main thread
            self.error = error
        finally:
            self._ended.set()

    def _work(self):
        """The task's native work (runs on the worker thread; no bpy)."""
        raise NotImplementedError

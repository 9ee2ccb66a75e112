"""What every SHGI operator that runs a NativeTask (engine/native_task.py) shares: from a script
or in background mode (execute) it waits for the task, and Ctrl-C (SIGINT, which background
Blender would otherwise keep for renders) cancels it, during the export too; from the UI
(invoke) it runs modal, a window-manager timer shows the task's progress in the status bar (and,
with PROGRESS_BAR, the window's progress indicator) and Esc cancels it. The export before the
task runs on Blender's main thread in one go: a window handles Esc only once it has ended.

A subclass implements _start(context) -> a started task or None (after reporting why),
_finish(context, task) -> the operator's result, _progress(task) -> (fraction, stage), and may
override _tick(context, task), called on every timer event before the progress is shown, and
_waiting(task), called on every wake of a waiting execute() (a headless run's log lines).
"""

from .keyboard_interrupt import keyboard_interrupts, sigint_watch

TIMER_SECONDS = 0.1
# How often a waiting execute() wakes; a Ctrl-C also interrupts the wait at once.
WAIT_SECONDS = 0.1


class ModalTaskOperator:
    STATUS_PREFIX = "SHGI: "
    STATUS_IDLE = "working"  # shown while the task has no stage yet
    PROGRESS_BAR = False

    def execute(self, context):
        task = None
        try:
            with keyboard_interrupts(), sigint_watch() as interrupted:
                task = self._start(context)
                while task is not None and not task.wait(WAIT_SECONDS):
                    self._waiting(task)
                    if interrupted():  # a Ctrl-C whose KeyboardInterrupt was swallowed
                        raise KeyboardInterrupt
        except KeyboardInterrupt:
            if task is None:
                self.report({"WARNING"}, f"{self.STATUS_PREFIX}interrupted (Ctrl-C) while "
                            "preparing; nothing was started")
                return {"CANCELLED"}
            task.cancel()
            task.wait()
        if task is None:
            return {"CANCELLED"}
        return self._finish(context, task)

    def invoke(self, context, _event):
        if context.window is None:  # no window to poll from (background mode): wait instead
            return self.execute(context)
        self._task = self._start(context)
        if self._task is None:
            return {"CANCELLED"}
        window_manager = context.window_manager
        self._timer = window_manager.event_timer_add(TIMER_SECONDS, window=context.window)
        if self.PROGRESS_BAR:
            window_manager.progress_begin(0.0, 1.0)
        window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self._task.cancel()
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        self._tick(context, self._task)
        window_manager = context.window_manager
        if self._task.running:
            fraction, stage = self._progress(self._task)
            if self.PROGRESS_BAR:
                window_manager.progress_update(fraction)
            context.workspace.status_text_set(
                f"{self.STATUS_PREFIX}{stage or self.STATUS_IDLE} {100 * fraction:.0f}% "
                "(Esc cancels)")
            return {"PASS_THROUGH"}
        window_manager.event_timer_remove(self._timer)
        if self.PROGRESS_BAR:
            window_manager.progress_end()
        context.workspace.status_text_set(None)
        return self._finish(context, self._task)

    def _tick(self, context, task):
        pass

    def _waiting(self, task):
        pass

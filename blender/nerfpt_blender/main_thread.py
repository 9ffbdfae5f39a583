"""Running a function on Blender's main thread from another thread.

F12 renders in a job thread, but Blender's glTF exporter is an operator that reads bpy.context and evaluates the
view layer: it must run on the main thread. A persistent timer (bpy.app.timers, main thread) runs what other
threads queue here. In background mode (`blender -b`) the render runs on the main thread itself and the function
is called directly. No bpy import at module level, so the queue can be tested without Blender.
"""

import queue
import threading

_tasks = queue.Queue()
_TIMER_INTERVAL_S = 0.05


class _Task:
    def __init__(self, fn):
        self.fn = fn
        self.done = threading.Event()
        self.lock = threading.Lock()
        self.state = "queued"  # -> "running" (the main thread took it) or "abandoned" (the caller gave up)
        self.result = None
        self.error = None


def is_main_thread():
    return threading.current_thread() is threading.main_thread()


def drain():
    """Runs every queued task (called by the timer on the main thread; tests call it directly)."""
    while True:
        try:
            task = _tasks.get_nowait()
        except queue.Empty:
            return
        with task.lock:
            if task.state == "abandoned":
                continue
            task.state = "running"
        try:
            task.result = task.fn()
        except BaseException as e:  # handed to the waiting thread, which raises it there
            task.error = e
        task.done.set()


def _timer():
    drain()
    return _TIMER_INTERVAL_S


def call(fn, should_cancel=lambda: False, poll_s=0.05):
    """fn() on the main thread; its result, or its exception raised here. Returns None without running fn when
    should_cancel() turns true before the main thread picked it up."""
    if is_main_thread():
        return fn()
    task = _Task(fn)
    _tasks.put(task)
    while not task.done.wait(poll_s):
        if should_cancel():
            with task.lock:
                if task.state == "queued":
                    task.state = "abandoned"  # the main thread will skip it
                    return None
            task.done.wait()  # already running: it finishes (an export takes seconds at most)
            break
    if task.error is not None:
        raise task.error
    return task.result


def register():
    import bpy

    if not bpy.app.timers.is_registered(_timer):
        bpy.app.timers.register(_timer, first_interval=_TIMER_INTERVAL_S, persistent=True)


def unregister():
    import bpy

    if bpy.app.timers.is_registered(_timer):
        bpy.app.timers.unregister(_timer)

"""An iterator's items made ahead in a second thread: frames read, decoded and prepared while earlier ones are tracked.

Reading a bag, decoding an image and most of OpenCV's work release Python's global lock, so a second thread that
makes the next frames overlaps them with the tracking of the current one (``gpo.pipeline.run.odometry`` with
``threads``). The items come out in their order, whatever the threads do.
"""

from __future__ import annotations

import queue
import signal
import threading
from collections.abc import Iterable, Iterator
from typing import TypeVar

Item = TypeVar("Item")

WAIT_S = 0.1  # how often a blocked producer looks whether it should stop, seconds


def read_ahead(items: Iterable[Item], depth: int = 4) -> Iterator[Item]:
    """The items of ``items`` in their order, made by a background thread at most ``depth`` ahead of the consumer.

    An exception raised while making an item is raised here, in that item's place, after the items before it. Closing
    the iterator (a loop over it left by ``break`` or an exception, Ctrl-C included) stops the thread once the item
    it is making is made; the iterator ``items`` is then left where it stopped.
    """
    if depth < 1:
        raise ValueError(f"read_ahead needs depth >= 1, got {depth}")
    ready: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def offer(entry) -> bool:
        while not stop.is_set():
            try:
                ready.put(entry, timeout=WAIT_S)
                return True
            except queue.Full:
                continue
        return False

    def produce() -> None:
        if hasattr(signal, "pthread_sigmask"):  # Ctrl-C and SIGTERM go to the main thread, which handles them
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
            for item in items:
                if not offer((item, None, False)):
                    return
        except BaseException as error:  # handed to the consumer, who raises it in the item's place
            offer((None, error, True))
            return
        offer((None, None, True))

    thread = threading.Thread(target=produce, name="read-ahead", daemon=True)
    thread.start()
    try:
        while True:
            item, error, done = ready.get()
            if error is not None:
                raise error
            if done:
                return
            yield item
    finally:
        stop.set()
        thread.join()

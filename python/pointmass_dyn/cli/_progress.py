"""A text progress bar on stderr for the long commands (sweep, balance)."""

from __future__ import annotations

import time


def progress_bar(total: int, stream, always: bool, unit: str = "runs"):
    """``progress(done, B)`` drawing a text bar on ``stream`` (after 0.5 s unless ``always``),
    and ``finish()`` ending its line."""
    start = time.perf_counter()
    state = {"shown": False, "done": 0}

    def draw(done: int) -> None:
        elapsed = time.perf_counter() - start
        frac = done / total if total else 1.0
        bar = "#" * int(30 * frac)
        left = f", ~{elapsed * (total - done) / done:.0f} s left" if 0 < done < total else ""
        stream.write(f"\r  [{bar:<30}] {done}/{total} {unit}, {elapsed:.1f} s{left}   ")
        stream.flush()
        state["shown"] = True

    def report(done: int, count: int) -> None:
        state["done"] = done
        if always or time.perf_counter() - start >= 0.5:
            draw(done)

    def finish(done: int | None = None) -> None:
        """Ends the bar at ``done`` (None: the last count reported)."""
        if state["shown"] or always:
            draw(state["done"] if done is None else done)
            stream.write("\n")
            stream.flush()

    return report, finish

"""Stage 2's timing figure for the decks, drawn only from its record (``slides/records/whitted.json``, made by
``cs451 slides record whitted``): nothing is timed while a deck is built."""
from __future__ import annotations

from typing import Any

from ...progress import Progress
from ...slides.canvas import plain_log_ticks, plot_row
from ...slides.records import declare_record
from ...slides.registry import Drawn, slide_figure

declare_record("whitted", "Whitted's scene on the reference's numpy path: frame time and error against a converged "
                          "render over image size, samples per pixel and the β cut-off", f"{__package__}.bench")


def _within_noise(rows: list[dict[str, Any]]) -> list[tuple[str, str]]:
    """Pairs of neighbouring rows (in the order given) whose timings overlap: each one's slowest run slower than the
    other's fastest, so that their order in time is not measured."""
    return [(a["value"], b["value"]) for a, b in zip(rows, rows[1:])
            if a["cpu_seconds_min"] <= b["cpu_seconds_max"] and b["cpu_seconds_min"] <= a["cpu_seconds_max"]]


SWEEP_STYLE = {"size": ("o", "tab:blue"), "spp": ("s", "tab:green"), "cut-off": ("^", "tab:red")}


def _is_default(row: dict[str, Any], params: dict[str, Any]) -> bool:
    """The configuration every sweep shares: the largest size, the default samples and cut-off."""
    return ([row["width"], row["height"]] == list(params["top"]) and row["spp"] == params["default"]["spp"]
            and row["cutoff"] == params["default"]["min_weight"])


@slide_figure("bench-whitted",
         "Whitted's scene on the reference's numpy path, from its record (slides/records/whitted.json, made by cs451 "
         "slides record whitted, never timed while the deck is built): frame time against RMS error from a converged "
         "render over image size, samples per pixel and the β cut-off, with each cut-off up close, its runs' spread "
         "and its rays",
         kit=("cs451.slides.records",), records=("whitted",))
def _bench_whitted(bar: Progress) -> Drawn:
    from ...slides.records import facts as record_facts, load_record, provenance
    record = load_record("whitted")
    rows, params = record["rows"], record["params"]
    default = params["default"]
    cutoffs = sorted((r for r in rows if r["sweep"] == "cut-off"), key=lambda r: -r["cutoff"])
    tied = _within_noise(cutoffs)

    def overview(ax: Any) -> None:
        for sweep, (marker, colour) in SWEEP_STYLE.items():
            points = [r for r in rows if r["sweep"] == sweep]
            xs, ys = [r["cpu_seconds"] for r in points], [r["rms_error"] for r in points]
            ax.plot(xs, ys, marker=marker, color=colour, ls=":", ms=7)
            for x, y, r in zip(xs, ys, points):
                if sweep != "cut-off" and not _is_default(r, params):
                    above = sweep == "size"
                    ax.annotate(f"{r['value']} spp" if sweep == "spp" else r["value"], (x, y),
                                xytext=(-4 if above else 6, 8 if above else -8), textcoords="offset points",
                                ha="right" if above else "left", va="bottom" if above else "top")
        base = next(r for r in rows if _is_default(r, params))
        ax.annotate("the default", (base["cpu_seconds"], base["rms_error"]), xytext=(8, 8), textcoords="offset points",
                    va="bottom")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("seconds a frame (median CPU time)")
        ax.set_ylabel("RMS error against converged")
        ax.set_title("every sweep")
        ax.grid(True, which="both", alpha=0.25)
        ax.margins(x=0.25, y=0.2)
        plain_log_ticks(ax)

    def up_close(ax: Any) -> None:
        xs, ys = [r["rays"] / 1e3 for r in cutoffs], [r["cpu_seconds"] for r in cutoffs]
        ax.errorbar(xs, ys, yerr=[[r["cpu_seconds"] - r["cpu_seconds_min"] for r in cutoffs],
                                  [r["cpu_seconds_max"] - r["cpu_seconds"] for r in cutoffs]],
                    fmt="^:", color=SWEEP_STYLE["cut-off"][1], ms=7, capsize=4)
        for x, y, r in zip(xs, ys, cutoffs):
            ax.annotate(f"β {r['value']}", (x, y), xytext=(7, -9), textcoords="offset points", ha="left",
                        va="top")
        ax.set_xlabel("thousand rays cast (the tracer's counters)")
        ax.set_ylabel("CPU seconds a frame")
        ax.set_title("the cut-off: rays and time (bars: every run)")
        ax.grid(True, which="both", alpha=0.25)
        ax.margins(x=0.15, y=0.3)

    w, h = params["top"]
    said = ("Within noise (their runs overlap): " + "; ".join(f"β {a} and β {b}" for a, b in tied) if tied
            else "No two neighbouring cut-offs' runs overlap")
    title = f"Whitted's scene, {w}×{h}: time against error (the reference on its numpy path)"
    legend = [(f"image size ({default['spp']} spp, cut-off {default['min_weight']:g})",
               {"color": SWEEP_STYLE["size"][1], "marker": "o", "ls": ":"}),
              (f"samples per pixel ({w}×{h})", {"color": SWEEP_STYLE["spp"][1], "marker": "s", "ls": ":"}),
              (f"β cut-off ({w}×{h}, {default['spp']} spp)", {"color": SWEEP_STYLE["cut-off"][1], "marker": "^",
                                                              "ls": ":"})]
    converged = params["converged"]
    note = (f"Time: the CPU seconds of a frame (the wall clock, which other work on the machine stretches, is in the "
            f"record). Converged: {converged['spp']} spp, cut-off {converged['min_weight']:g}, depth "
            f"{converged['max_depth']}. {said}. {provenance(record)}.")
    image = plot_row(1160, 330, [overview, up_close], title, legend, note, widths=[1.15, 1])
    bar.advance(note="plot")
    return Drawn(image, {"rows": rows, "within_noise": tied, "converged": converged, "top": [w, h],
                         **record_facts(record)})

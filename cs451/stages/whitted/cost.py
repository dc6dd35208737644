"""What a Whitted render asks of the machine, judged from the scene before any ray is cast: memory for the
camera rays and light samples, and time for the shadow tests (:func:`cs451.limits.refuse_over_budget`)."""
from __future__ import annotations

from ...scene import AreaLight, Scene
from .options import WhittedOptions


#: bytes per camera ray of a frame (its sub-pixel samples included), measured on the reference: 100-110 at
#: 320 × 240 with 16 and 64 samples per pixel; with margin
RAY_BYTES = 160
#: bytes per light sample (an area light is a grid of them, each a row of the frame's light table), with margin
LIGHT_SAMPLE_BYTES = 512
#: shading-point × light-sample tests per second of the reference: 40 million measured on a 2-core machine
#: (128 × 96 pixels, 1,024 samples of an area light, the Whitted scene); halved for a slower laptop
LIGHT_TESTS_PER_S = 20e6


def estimate(scene: Scene, size: tuple[int, int] | None, opts: WhittedOptions) -> list:
    """Memory for the camera rays and the light samples; time for the shadow tests every ray's hit makes."""
    from ...limits import Cost
    w, h = size or (scene.image.width, scene.image.height)
    rays = w * h * opts.spp
    costs = [Cost("options.whitted.spp", RAY_BYTES * rays, f"{rays:,} camera rays ({w}x{h}, {opts.spp} per pixel)")]
    for k, light in enumerate(scene.lights):
        if isinstance(light, AreaLight):
            n, where = (opts.light_samples, "options.whitted.light_samples") if opts.light_samples else \
                (light.samples, f"lights[{k}].samples")
            costs.append(Cost(where, LIGHT_SAMPLE_BYTES * n, f"{rays:,} camera rays × {n:,} light samples",
                              seconds=rays * n / LIGHT_TESTS_PER_S))
    return costs


#: camera rays per second of the reference where no area light multiplies the work (the Whitted scene, 400 × 300:
#: about 2 million on two cores); halved for a slower laptop
RAYS_PER_S = 1e6
#: a render estimated past this many seconds is traced in bands of about BAND_SECONDS each, under a progress bar
BANDED_SECONDS = 1.0
BAND_SECONDS = 0.25


def trace_seconds(scene: Scene, rays: int, opts: WhittedOptions) -> float:
    """About how long tracing ``rays`` camera rays takes the reference: each, and its shadow tests."""
    samples = sum((opts.light_samples or light.samples) for light in scene.lights if isinstance(light, AreaLight))
    return rays / RAYS_PER_S + rays * samples / LIGHT_TESTS_PER_S


def bands(rays: int, seconds: float) -> list[slice]:
    """The camera rays in bands of about BAND_SECONDS each (one band for a short render), 256 at most."""
    count = 1 if seconds <= BANDED_SECONDS else min(int(seconds / BAND_SECONDS) + 1, 256, rays)
    edges = [rays * k // count for k in range(count + 1)]
    return [slice(a, b) for a, b in zip(edges, edges[1:])]

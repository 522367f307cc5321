"""Speed of the camera models on a whole image: unproject every pixel, project every ray.

    python benchmarks/camera_speed.py [--repeat N]

Prints the best of N runs in milliseconds per full image and in megapixels per second.
"""

import argparse
import timeit

from gpo.cameras import T265_LIKE, Pinhole

DOWNWARD = Pinhole(fx=600.0, fy=600.0, cx=376.0, cy=240.0, dist=(-0.28, 0.09, 1e-3, -8e-4), width=752, height=480)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    print(f"{'camera':<28}{'operation':<12}{'ms / image':>12}{'Mpx / s':>10}")
    for name, camera in (("EUCM 848x800 (T265-like)", T265_LIKE), ("pinhole+radtan 752x480", DOWNWARD)):
        pixels = camera.pixel_grid()
        rays, _ = camera.unproject(pixels)
        megapixels = pixels[..., 0].size / 1e6
        for operation, function, argument in (
            ("unproject", camera.unproject, pixels),
            ("project", camera.project, rays),
        ):
            seconds = min(timeit.repeat(lambda f=function, a=argument: f(a), number=1, repeat=args.repeat))
            print(f"{name:<28}{operation:<12}{seconds * 1e3:>12.1f}{megapixels / seconds:>10.1f}")


if __name__ == "__main__":
    main()

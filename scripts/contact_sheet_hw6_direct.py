#!/usr/bin/python3
"""Contact sheet of the hw6 direct-lighting scenes (BRDFs and object lights): reference | clrt | |difference| x 8, one row per scene.

usage: /usr/bin/python3 scripts/contact_sheet_hw6_direct.py OUT.png [--spp N] [--clrt BIN]

Renders the five brdf_* scenes (1 spp, --ldr-quantize floor) and the cornell boxes
cornellbox_jaroslav_diffuse/_glossy (point light), _diffuse_area (LightMesh), _glossy_area_sphere (LightSphere) (the scene's 100 spp unless --spp; tone-mapped PNG, the course's
Photographic TMO) from ../shared/scenes/hw6 and compares their PNGs with the course's reference PNGs.
Each row's title gives the PSNR of the 8-bit images. Needs python3-matplotlib and python3-numpy.
"""
import argparse
import os
import subprocess
import sys
import tempfile

SCENES = ["brdf_phong_original", "brdf_phong_modified", "brdf_blinnphong_original",
          "brdf_blinnphong_modified_normalized", "brdf_torrancesparrow",
          "cornellbox_jaroslav_diffuse", "cornellbox_jaroslav_glossy",
          "cornellbox_jaroslav_diffuse_area", "cornellbox_jaroslav_glossy_area_sphere"]


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--spp", type=int, default=0, help="cornell boxes: samples per pixel (0: the scene's 100)")
    ap.add_argument("--clrt", default=os.path.join(here, "..", "build", "clrt"))
    ap.add_argument("--shared", default=os.path.join(here, "..", "..", "shared"))
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    hw6 = os.path.join(args.shared, "scenes", "hw6")
    fig, axes = plt.subplots(len(SCENES), 3, figsize=(9, 3 * len(SCENES)))
    with tempfile.TemporaryDirectory() as tmp:
        for row, name in enumerate(SCENES):
            cmd = [args.clrt, "render", os.path.join(hw6, name + ".xml"), "-o", tmp, "--ldr-quantize", "floor"]
            if args.spp and name.startswith("cornell"):
                cmd += ["--spp", str(args.spp)]
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            ref = plt.imread(os.path.join(hw6, "_reference_outputs", name + ".png"))[..., :3]
            img = plt.imread(os.path.join(tmp, name + ".png"))[..., :3]
            diff = np.abs(ref.astype(np.float64) - img.astype(np.float64))
            mse = np.mean((diff * 255) ** 2)
            psnr = float("inf") if mse == 0 else 10 * np.log10(255 ** 2 / mse)
            for col, (im, title) in enumerate([(ref, "reference"), (img, "clrt"), (np.clip(diff * 8, 0, 1), "|diff| x 8")]):
                ax = axes[row][col]
                ax.imshow(im)
                ax.set_xticks([])
                ax.set_yticks([])
                ax.set_title(f"{name}\n{title}" + (f" ({psnr:.1f} dB)" if col == 2 else ""), fontsize=7)
            print(f"{name}: PSNR {psnr:.2f} dB", flush=True)
    fig.tight_layout()
    fig.savefig(args.out, dpi=80)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""How does it fit? The T-shirt on the mannequin, and its fit maps: stretch, pressure, gap, ease.

Run:  python examples/tshirt_fit.py          (writes out/tshirt_fit/…, its fit maps in out/tshirt_fit/fit/)

The same from the command line: ``tailor drape panels/tshirt.json --fit`` (or ``tailor fit RUN_DIR``
on a run already written). TAILOR_QUICK=1 uses a coarse 4 cm mesh and 2 frames (about 15 s).
"""

import os
from pathlib import Path

import tailor
from tailor.fit import FitSource, fit_map
from tailor.io.body_files import read_body
from tailor.io.fit_files import write_fit
from tailor.io.garment import write_drape

quick = os.environ.get("TAILOR_QUICK") == "1"
pattern = tailor.read_pattern(Path(__file__).resolve().parent.parent / "panels" / "tshirt.json")
result = tailor.drape(pattern, read_body("mannequin"), frames=2 if quick else 10, resolution=0.04 if quick else 0.02)

source = FitSource.of_drape(result)
fit = fit_map(source)  # the last frame: arrays per face (stretch_max, …) and per vertex (contact_force, …)
out = write_drape(result, Path("out") / "tshirt_fit", overwrite=True)
write_fit([fit], out / "fit", source.bodies)

weight = fit.contact_force[:, 2].sum()
print(f"the body carries {weight:.2f} N of the T-shirt; largest stretch {fit.stretch_max.max():.1f} % "
      f"(jersey's wearable stretch: {fit.wearable.max():.0f} %), largest pressure {fit.pressure_kpa.max():.3f} kPa")
for name in fit.ease:
    row = fit.at_landmark(name)
    print(f"  {name:16s} body {row['body_cm']:6.1f} cm, garment {row['garment_cm']:6.1f} cm, ease {row['ease_cm']:+5.1f} cm")
print(f"maps: {out}/fit/fit_{fit.frame:04d}.png, pressure_{fit.frame:04d}.png, fit_{fit.frame:04d}.ply, fit.csv, ease.csv")

"""Write the example density grids (`cloudcore.scenes.interop.example_grids`) as OpenVDB files to import:
`python scripts/make_vdb_examples.py FOLDER` writes FOLDER/sphere.vdb and FOLDER/noise.vdb."""

import sys
from pathlib import Path

from cloudcore.scenes.interop.example_grids import noise_grid, sphere_grid
from cloudcore.scenes.interop.vdb import write_density_grids

if __name__ == "__main__":
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    write_density_grids(folder / "sphere.vdb", [sphere_grid()])
    write_density_grids(folder / "noise.vdb", [noise_grid()])
    print(f"wrote {folder / 'sphere.vdb'} and {folder / 'noise.vdb'}")

import sys

from app.main import main

# the relighting worker (`cloudcore.light.relighting`) is spawned and imports this module again: only the
# editor's own process runs it
if __name__ == "__main__":
    sys.exit(main())

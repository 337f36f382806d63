"""Where the surrogates' force errors sit (eccentricity, journal speed), held out and along the orbits.

    python experiments/error_map.py

The study is fluidfilm.studies.error_map; config conf/error_map.yaml.
"""
from fluidfilm.studies import error_map
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(error_map, "the error map")

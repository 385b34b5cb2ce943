"""``python -m radarsnn``: the ``radarsnn`` command without its installed script.

Examples
--------
>>> import subprocess, sys
>>> done = subprocess.run([sys.executable, "-m", "radarsnn", "--version"],
...                       capture_output=True, text=True)
>>> done.returncode, done.stdout.startswith("radarsnn ")
(0, True)
"""

import sys

from radarsnn.cli import main

if __name__ == "__main__":
    sys.exit(main())

import sys

from executive.cli import main

sys.exit(main())

"""`python -m llfsm.idl` (`make msgs`): regenerate the shipped message modules (llfsm.idl.shipped)."""

import sys

from .shipped import main

sys.exit(main())

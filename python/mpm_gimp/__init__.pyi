from typing import Any

import numpy as np

from . import f64 as f64
from ._api import MpmError as MpmError
from ._api import Particles as Particles
from ._api import World as World
from ._types import *

precision: str
dtype: type[np.floating[Any]]

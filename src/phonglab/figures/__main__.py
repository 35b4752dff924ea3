"""``python -m phonglab.figures [DIR]``: write the figures docs/notebooks.md shows (``make notebook-figures``)."""

import sys

from .docs import write_doc_images

for p in write_doc_images(sys.argv[1] if len(sys.argv) > 1 else "docs/img"):
    print(p)

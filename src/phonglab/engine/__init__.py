"""The rendering engine: a scene file to images with their error, and how those images are kept.

:mod:`.scenes` resolves and loads a scene (names from the package's ``scenes_xml/``);
:mod:`.render` renders it in passes (the one loop around ``mi.render``), :mod:`.adaptive` with
samples where the error is, against the one reference cache of :mod:`.references`;
:mod:`.metrics` defines each error once and :mod:`.compare` holds two images against each
other; :mod:`.compare_models` renders one scene with the seed's model and with light transport.
What a render writes: :mod:`.exr` (OpenEXR with provenance, written atomically),
:mod:`.tonemap` (PNG previews) and :mod:`.outputs` (a render's file set, checked before any
work and replaced as one).

Importing this package imports nothing; its modules import Mitsuba or numpy.
"""

"""The application layer: the ``workbench`` command line (:mod:`.cli`), ``workbench verify``
(:mod:`.verify`) and the report (:mod:`.report`). It reads the studies' datasets and figures;
nothing imports it (layers: ``workbench`` core ← ``sph``/``fem_reference`` ← ``studies`` ← this)."""

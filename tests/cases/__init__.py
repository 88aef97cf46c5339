"""Cases that both the tests and the benchmarks use (tests never import benchmarks/):
the inpainting corpus (inpaint_corpus.py), the synthetic slot cases (inpaint_slots.py),
the layout's measures (layout_metrics.py) and the cast-shadow rule of the real footage's
truth (cast_shadow.py). Imported as ``tests.cases.<module>`` from the repository's root
(pyproject.toml gives pytest that root as its pythonpath)."""

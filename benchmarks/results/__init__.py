"""docs/results.md, made by benchmarks/results_doc.py (the entry point: its docstring lists the commands), by job:

    files.py         where the inputs live, the protocol's variants, reading the small result files (docs/results/)
    collect.py       the run directories' artifacts -> those small result files
    figures.py       the page's figures, from the result files alone
    tables.py        the arithmetic and the formatting every table uses (means, paired intervals, programs shown)
    claims.py        the paper's claims: records in claims.toml, checked by one generic function
    sections.py      the sections of one training seed (a task's table and claims, at a glance, selection, stress)
    appendix.py      the sections of appendices D and E and of the VMAS scenarios
    seed_sections.py the sections over training seeds
    render.py        the template's placeholders -> the page

Imports go one way: files <- tables <- claims <- sections, appendix, seed_sections <- render <- results_doc.py.
"""

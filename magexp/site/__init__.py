"""The results website: the committed ``results/`` (the report, the appendix, ``claims.csv``,
``summary.csv``, the figures and CSVs) as pages of the documentation site that ``make docs`` builds,
through the mkdocs hook :mod:`magexp.site.hooks`: a landing page, one page per paper with its
readings side by side and its appendix, and a claims explorer. It reads ``results/`` and writes only
into the build."""

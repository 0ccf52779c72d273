"""rik, the Real-IKEA kit: articulated furniture for contact-rich robot manipulation.

Importing :mod:`rik` is cheap: it imports no simulator, renderer or learning library.
"""

__version__ = "0.1.0"

#: Version of the catalog data format (the YAML files and the JSON that ``rik catalog`` prints).
CATALOG_SCHEMA = 1

"""Data package: the jinja2 templates of the case dictionaries, shipped inside foamsilo.

Not Python code: foamsilo.resources.templates_dir() finds this directory.
"""

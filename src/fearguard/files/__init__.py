"""Reading files: the one strict, bounded reader every file format goes through, and importing a user's
``module:function``.
"""

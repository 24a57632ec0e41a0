"""``python -m vistrack.cli``: the ``vistrack`` command."""

from . import main

if __name__ == "__main__":
    main()

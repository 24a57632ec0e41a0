"""``vistrack run``: one video tracked, with its track file, annotated video and summary."""

"""Scenes: the Mitsuba XML loader (with the upgrade of Mitsuba 0.5/0.6 files), the builtin scenes, the host
`Scene` and its upload to the device (`SceneDevice`)."""

"""The pbrt-v4 scene format: reader.py reads the directives (tokens.py, params.py) and translates
shapes (shapes.py), materials and textures (materials.py), lights (lights.py), the camera and film
(camera.py) and spectra (spectra.py, named_spectra.py) into the scene object that
scene.build_scene builds, as the Mitsuba XML loader's."""

"""glTF 2.0 files (.gltf, .glb): reader.py walks the scene graph (meshes, cameras,
KHR_lights_punctual) with accessors.py's typed arrays and images, materials.py maps the
metallic-roughness materials and their extensions, into the scene object scene.build_scene
builds (docs/guide/gltf.md)."""

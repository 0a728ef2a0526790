"""restir's two-sided area emitter (an area emitter's `twosided`, which the pbrt-v4 reader gives its
two-sided area lights and the glTF reader its double-sided emissive materials): its back emits
as its front does, through every way the path tracer reaches it (the camera seeing it, light
sampling from the point lit, BSDF samples that hit it, and the MIS between the last two).

A light over a floor facing down (one-sided), against the same light turned to face up with
`twosided` on: nothing lies above it, so the second scene's extra light leaves, and the two
images are equal in expectation. Welch z per pixel and tile with both renders' variances (alpha
1e-3 per channel over the image); the minimum detectable bias is asserted below 2%. The
light turned up without `twosided` lights nothing, which the test would see. The methods that
reuse paths are checked on two-sided emitters by the matrices' normalmaps-twosided scene."""
import restir
from tests.helpers import check

SCENE = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 1.2, -4" target="0, 0.4, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
            <rfilter type="box"/></film></sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.4"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.8" y="0.5"/><rotate x="1" angle="{angle}"/><translate y="1.2"/></transform>
        <emitter type="area"><rgb name="radiance" value="4, 5, 6"/>{twosided}</emitter>
    </shape>
</scene>
"""


def render(tmp_path, name, angle, twosided, seed):
    path = tmp_path / f"{name}.xml"
    flag = '<boolean name="twosided" value="true"/>' if twosided else ""
    path.write_text(SCENE.format(angle=angle, twosided=flag))
    return restir.render(restir.load_scene(str(path)), method="pt", spp=8, frames=32, max_depth=4, seed=seed)


def test_a_two_sided_emitter_lights_from_its_back_as_from_its_front(tmp_path):
    down = render(tmp_path, "down", 90, False, seed=1)
    up_twosided = render(tmp_path, "up", -90, True, seed=2)
    assert down.image.mean() > 0.05
    rep = check(up_twosided, down.image, down.batch_variance_of_mean, other=down)
    assert rep.mdb < 0.02
    assert render(tmp_path, "up-onesided", -90, False, seed=3).image.max() == 0.0

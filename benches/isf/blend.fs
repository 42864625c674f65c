/*{
    "DESCRIPTION": "The blend node's normal mode as an ISF filter: indra's benchmark of an ISF pass against the same effect written in WGSL (src/techniques/blend/blend.wgsl)",
    "CREDIT": "indra",
    "ISFVSN": "2",
    "INPUTS": [
        { "NAME": "below", "TYPE": "image" },
        { "NAME": "over", "TYPE": "image" },
        { "NAME": "opacity", "TYPE": "float", "DEFAULT": 0.5, "MIN": 0.0, "MAX": 1.0 }
    ]
}*/

void main() {
    vec4 b = IMG_THIS_PIXEL(below);
    vec4 o = IMG_THIS_PIXEL(over);
    float a = clamp(opacity, 0.0, 1.0) * clamp(o.a, 0.0, 1.0);
    gl_FragColor = vec4(mix(b.rgb, o.rgb, a), b.a + a * (1.0 - b.a));
}

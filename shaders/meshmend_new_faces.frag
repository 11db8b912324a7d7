// MeshMend new-faces view: which faces the last MeshMend filter that rebuilt
// the layer made, from the per-face attribute meshmend_face_change
// (0 kept, 1 cut from an input face, 2 new: hole patches, stitches) that
// "MeshMend: Prepare Shader View" moved into the texture coordinates:
// u = 4 change + b0, v = 300 + 4 boundary_mask + b1. Regions of made faces
// are outlined.
uniform vec3 kept_colour;
uniform vec3 cut_colour;
uniform vec3 new_colour;
uniform float outline_width;

varying vec3 eyePosition;
varying vec3 eyeNormal;
varying vec2 channel;

float lighting()
{
  vec3 n = eyeNormal;
  if (dot(n, n) < 1e-12)
    n = cross(dFdx(eyePosition), dFdy(eyePosition));
  float facing = abs(dot(normalize(n), normalize(-eyePosition)));
  return 0.3 + 0.7 * facing;
}

vec3 noValues()
{
  float stripe = step(0.5, fract((gl_FragCoord.x + gl_FragCoord.y) / 24.0));
  return mix(vec3(0.62), vec3(0.48), stripe);
}

float boundaryDistance(float mask, vec3 b)
{
  float nearest = 1e6;
  if (mod(mask, 2.0) > 0.5) nearest = min(nearest, b.z / max(fwidth(b.z), 1e-6));
  if (mod(floor(mask / 2.0), 2.0) > 0.5) nearest = min(nearest, b.x / max(fwidth(b.x), 1e-6));
  if (mask > 3.5) nearest = min(nearest, b.y / max(fwidth(b.y), 1e-6));
  return nearest;
}

void main()
{
  float light = lighting();
  float tag = floor(channel.y / 100.0 + 0.5) * 100.0;
  if (tag != 300.0) {
    gl_FragColor = vec4(noValues() * light, 1.0);
    return;
  }
  float rest = channel.y - tag;
  float mask = floor(rest / 4.0 + 0.375);
  float change = floor(channel.x / 4.0 + 0.375);
  vec3 b;
  b.x = channel.x - 4.0 * change;
  b.y = rest - 4.0 * mask;
  b.z = 1.0 - b.x - b.y;
  vec3 colour = change > 1.5 ? new_colour : change > 0.5 ? cut_colour : kept_colour;
  float edge = boundaryDistance(mask, b);
  colour *= 1.0 - 0.75 * (1.0 - smoothstep(0.5 * outline_width, 0.5 * outline_width + 1.0, edge));
  gl_FragColor = vec4(colour * light, 1.0);
}

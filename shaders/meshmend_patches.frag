// MeshMend patch view: a colour per patch id (the colours "MeshMend: Paint
// Surface Patches" paints, common/patches.cpp patchColour) and darkened
// patch boundaries, from the ids "MeshMend: Prepare Shader View" moved into
// the texture coordinates: u = 4 id + b0, v = 200 + 4 boundary_mask + b1.
uniform float boundary_width;
uniform float boundary_darkness;

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

// Hues a golden angle apart, saturation alternating with the id's parity.
vec3 patchColour(float id)
{
  float h = fract(id * 0.6180339887) * 6.0;
  float s = mod(id, 2.0) > 0.5 ? 0.55 : 0.75;
  float v = 0.95;
  float sector = floor(h);
  float f = h - sector;
  float p = v * (1.0 - s), q = v * (1.0 - s * f), t = v * (1.0 - s * (1.0 - f));
  if (sector < 0.5) return vec3(v, t, p);
  if (sector < 1.5) return vec3(q, v, p);
  if (sector < 2.5) return vec3(p, v, t);
  if (sector < 3.5) return vec3(p, q, v);
  if (sector < 4.5) return vec3(t, p, v);
  return vec3(v, p, q);
}

// Distance in pixels to the nearest boundary edge of this face.
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
  if (tag != 200.0) {
    gl_FragColor = vec4(noValues() * light, 1.0);
    return;
  }
  float rest = channel.y - tag;
  float mask = floor(rest / 4.0 + 0.375);
  float id = floor(channel.x / 4.0 + 0.375);
  vec3 b;
  b.x = channel.x - 4.0 * id;
  b.y = rest - 4.0 * mask;
  b.z = 1.0 - b.x - b.y;
  vec3 colour = patchColour(id);
  float edge = boundaryDistance(mask, b);
  float onLine = 1.0 - smoothstep(0.5 * boundary_width, 0.5 * boundary_width + 1.0, edge);
  colour *= 1.0 - boundary_darkness * onLine;
  gl_FragColor = vec4(colour * light, 1.0);
}

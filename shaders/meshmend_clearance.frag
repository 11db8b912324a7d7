// MeshMend clearance heat map: the distance each vertex keeps from the
// nearest non-adjacent face (vertex quality of "MeshMend: Measure Clearance",
// moved into the texture coordinates by "MeshMend: Prepare Shader View").
// Red below tau, a dark line at tau, above it a ramp from yellow (at the
// low end of colour_range) through green to blue (at its high end).
uniform float tau;
uniform vec2 colour_range;

varying vec3 eyePosition;
varying vec3 eyeNormal;
varying vec2 channel;

// Two-sided headlight, the normal from the geometry where none is given.
float lighting()
{
  vec3 n = eyeNormal;
  if (dot(n, n) < 1e-12)
    n = cross(dFdx(eyePosition), dFdy(eyePosition));
  float facing = abs(dot(normalize(n), normalize(-eyePosition)));
  return 0.3 + 0.7 * facing;
}

// Grey with diagonal stripes: this layer carries no clearance values.
vec3 noValues()
{
  float stripe = step(0.5, fract((gl_FragCoord.x + gl_FragCoord.y) / 24.0));
  return mix(vec3(0.62), vec3(0.48), stripe);
}

vec3 ramp(float t)
{
  vec3 nearColour = vec3(1.0, 0.85, 0.1);
  vec3 midColour = vec3(0.25, 0.75, 0.3);
  vec3 farColour = vec3(0.2, 0.4, 0.95);
  return t < 0.5 ? mix(nearColour, midColour, 2.0 * t) : mix(midColour, farColour, 2.0 * t - 1.0);
}

void main()
{
  float light = lighting();
  if (abs(channel.y - 100.0) > 0.5) {
    gl_FragColor = vec4(noValues() * light, 1.0);
    return;
  }
  float d = channel.x;
  vec3 colour;
  if (d < tau) {
    colour = vec3(0.92, 0.1, 0.08);
  } else {
    float low = colour_range.x, high = colour_range.y;
    float t = high > low ? clamp((d - low) / (high - low), 0.0, 1.0) : 1.0;
    colour = ramp(t);
  }
  float width = fwidth(d);
  if (tau > 0.0 && width > 0.0)
    colour = mix(vec3(0.08), colour, clamp(abs(d - tau) / width - 0.5, 0.0, 1.0));
  gl_FragColor = vec4(colour * light, 1.0);
}

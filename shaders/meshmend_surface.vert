// Vertex program shared by MeshMend's shaders: eye-space position and normal
// for the lighting, and the texture coordinates that carry MeshMend's values
// ("MeshMend: Prepare Shader View" writes them; see common/render_channels.h).
varying vec3 eyePosition;
varying vec3 eyeNormal;
varying vec2 channel;

void main()
{
  eyePosition = vec3(gl_ModelViewMatrix * gl_Vertex);
  eyeNormal = gl_NormalMatrix * gl_Normal;
  channel = gl_MultiTexCoord0.st;
  gl_Position = ftransform();
}

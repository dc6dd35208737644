"""S5, S6: shaders that reproduce OpenGL 1.x fixed-function lighting.

The kit puts ``#version 330`` and the declarations of every uniform and input
in front of your source (see ``GLSL_INTERFACE`` in ``cs451/stages/sphere/__init__.py``):
the vertex shader receives ``in_position`` and ``in_normal`` in object space;
the fragment shader writes ``frag_color``.
"""
from __future__ import annotations

# BEGIN SOLUTION
# The lighting equation of the OpenGL 2.1 specification, §2.14.1, in eye space.
# Shared by both shading models: Gouraud calls it per vertex, Phong per fragment.
LIGHTING_GLSL = """
vec3 fixed_function_lighting(vec3 p, vec3 n) {
    vec3 color = u_mat_emission + u_mat_ambient * u_global_ambient;
    vec3 v = u_local_viewer ? normalize(-p) : vec3(0.0, 0.0, 1.0);
    for (int i = 0; i < u_num_lights; ++i) {
        vec4 lp = u_light_position[i];
        vec3 l;
        float att = 1.0;
        if (lp.w != 0.0) {
            vec3 d = lp.xyz / lp.w - p;
            float dist = length(d);
            l = d / dist;
            vec3 k = u_light_attenuation[i];
            att = 1.0 / (k.x + k.y * dist + k.z * dist * dist);
        } else {
            l = normalize(lp.xyz);
        }
        float ndotl = max(dot(n, l), 0.0);
        vec3 term = u_mat_ambient * u_light_ambient[i] + ndotl * u_mat_diffuse * u_light_diffuse[i];
        if (ndotl > 0.0) {
            float ndoth = max(dot(n, normalize(l + v)), 0.0);
            float spec = u_mat_shininess == 0.0 ? 1.0 : pow(ndoth, u_mat_shininess);
            term += spec * u_mat_specular * u_light_specular[i];
        }
        color += att * term;
    }
    return clamp(color, 0.0, 1.0);
}
"""
# END SOLUTION


def gouraud_shaders() -> tuple[str, str]:
    """Per-vertex lighting, as glShadeModel(GL_SMOOTH): the colour is computed at each vertex and interpolated.

    Returns ``(vertex_source, fragment_source)`` without the ``#version`` line.
    """
    # BEGIN SOLUTION S5: light each vertex in eye space, pass the colour down, interpolate (handout §S5)
    vertex = LIGHTING_GLSL + """
out vec3 v_color;
void main() {
    vec4 p = u_model_view * vec4(in_position, 1.0);
    vec3 n = normalize(u_normal_matrix * in_normal);
    v_color = fixed_function_lighting(p.xyz / p.w, n);
    gl_Position = u_projection * p;
}
"""
    fragment = """
in vec3 v_color;
void main() {
    frag_color = vec4(v_color, 1.0);
}
"""
    return vertex, fragment
    # END SOLUTION


def phong_shaders() -> tuple[str, str]:
    """Per-fragment lighting (Phong shading): interpolate position and normal, light each pixel.

    Returns ``(vertex_source, fragment_source)`` without the ``#version`` line.
    """
    # BEGIN SOLUTION S6: pass eye-space position and normal down, renormalise, light per fragment (handout §S6)
    vertex = """
out vec3 v_position;
out vec3 v_normal;
void main() {
    vec4 p = u_model_view * vec4(in_position, 1.0);
    v_position = p.xyz / p.w;
    v_normal = u_normal_matrix * in_normal;
    gl_Position = u_projection * p;
}
"""
    fragment = LIGHTING_GLSL + """
in vec3 v_position;
in vec3 v_normal;
void main() {
    frag_color = vec4(fixed_function_lighting(v_position, normalize(v_normal)), 1.0);
}
"""
    return vertex, fragment
    # END SOLUTION

//! `arbvis info`: what the driver is and what it can do for ARB programs.

use arbvis_gl::{Backend, Caps, EXACT_FILTER, EXACT_INTERPOLATION};

/// How the texture units interpolate, from the largest error of a linear fetch
/// ([`arbvis_gl::Gpu::linear_filter_error`]).
pub fn filtering(filter_error: f32) -> String {
    if filter_error <= EXACT_FILTER {
        format!("f32 (largest error {filter_error:.1e})")
    } else {
        format!(
            "coarse (largest error {filter_error:.1e}, 1/{:.0} of a texel step): precise \
             programs interpolate in the shader",
            1.0 / filter_error
        )
    }
}

/// How attributes interpolate, from the largest distance (pixels) between an interpolated
/// coordinate and the pixel centre's ([`arbvis_gl::Gpu::interpolation_error`]).
pub fn interpolation(error: f32) -> String {
    if error <= EXACT_INTERPOLATION {
        format!("from the true vertices (largest error {error:.1e} pixel)")
    } else {
        format!(
            "from snapped vertices (largest error {error:.1e} pixel): precise programs take \
             samples from pixel centres"
        )
    }
}

/// Human-readable report of `caps` on `backend`, and the measured errors of linear
/// filtering and attribute interpolation.
pub fn format_info(
    backend: Backend,
    caps: &Caps,
    filter_error: f32,
    interpolation_error: f32,
) -> String {
    let yes = |b: bool| if b { "yes" } else { "no" };
    let mut s = String::new();
    s += &format!("backend:                 {}\n", backend.name());
    s += &format!("GL_VENDOR:               {}\n", caps.vendor);
    s += &format!("GL_RENDERER:             {}\n", caps.renderer);
    s += &format!("GL_VERSION:              {}\n", caps.version);
    s += &format!("profile:                 {}\n", caps.profile);
    s += &format!("software renderer:       {}\n", yes(caps.software));
    s += &format!(
        "GL_ARB_fragment_program: {}\n",
        yes(caps.arb_fragment_program)
    );
    s += &format!(
        "GL_ARB_vertex_program:   {}\n",
        yes(caps.arb_vertex_program)
    );
    s += &format!("texture image units:     {}\n", caps.max_texture_units);
    s += &format!("max 3D texture size:     {}\n", caps.max_3d_texture_size);
    s += &format!("max 2D texture size:     {}\n", caps.max_texture_size);
    s += &format!("linear filtering:        {}\n", filtering(filter_error));
    s += &format!(
        "interpolation:           {}\n",
        interpolation(interpolation_error)
    );
    for (name, l, frag) in [
        ("fragment", caps.fragment_limits, true),
        ("vertex", caps.vertex_limits, false),
    ] {
        s += &format!("ARB {name} program native limits:\n");
        s += &format!("  instructions:          {}\n", l.native_instructions);
        s += &format!("  temporaries:           {}\n", l.native_temporaries);
        if frag {
            s += &format!("  texture indirections:  {}\n", l.native_tex_indirections);
        }
        s += &format!("  local parameters:      {}\n", l.local_parameters);
    }
    s
}

/// `arbvis info --json`: the backend and the capabilities, with the fragment and vertex
/// program limits as nested objects (their fields share names), and the linear
/// filter's and the attribute interpolation's measured errors (`linear_filter_error`,
/// `interpolation_error` in pixels).
pub fn to_json(
    backend: Backend,
    caps: &Caps,
    filter_error: f32,
    interpolation_error: f32,
) -> String {
    #[derive(serde::Serialize)]
    struct Info<'a> {
        backend: &'a str,
        #[serde(flatten)]
        caps: &'a Caps,
        linear_filter_error: f32,
        interpolation_error: f32,
    }
    serde_json::to_string_pretty(&Info {
        backend: backend.name(),
        caps,
        linear_filter_error: filter_error,
        interpolation_error,
    })
    .unwrap_or_else(|e| format!("{{\"error\": {:?}}}", e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_nests_the_limits_and_names_the_backend() {
        let caps = Caps {
            renderer: "r".into(),
            ..Default::default()
        };
        let v: serde_json::Value =
            serde_json::from_str(&to_json(Backend::Osmesa, &caps, 3e-8, 1e-6)).unwrap();
        assert_eq!(v["backend"], "osmesa");
        assert!(v["fragment_limits"]["native_instructions"].is_number());
        assert!(v["vertex_limits"]["local_parameters"].is_number());
        assert!(v["linear_filter_error"].is_number());
        assert!(v["interpolation_error"].is_number());
    }
}

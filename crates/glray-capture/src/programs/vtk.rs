//! VTK 9's polygonal-data programs (vtkOpenGLPolyDataMapper, ParaView 5.11's VTK 9.2), as a
//! profile table. Read off the programs ParaView 5.11 builds (docs/compatibility.md,
//! ../shared/notes/paraview-gl.md): positions are shifted and scaled into the buffer and put
//! back by `MCVCMatrix`, so eye coordinates are `MCVCMatrix * vertexMC` and the projection is
//! `MCDCMatrix * inverse(MCVCMatrix)`; the light kit's lights come in eye coordinates as
//! directions of travel; colour by a scalar is `tcoord` interpolated and then looked up in the
//! colour map `colortexture`; the fragment is lit per pixel as
//! `ambient + sum(diffuse) * colour + sum(specular) * specular colour`, back faces with the
//! normal flipped.

use super::profile::Profile;

/// VTK 9.0-9.2's names.
pub const VTK9: Profile = Profile {
    name: "VTK 9 polygonal data",
    position: "vertexMC",
    normal: "normalMC",
    texcoord: "tcoord",
    color: "scalarColor",
    object_to_eye: "MCVCMatrix",
    object_to_clip: "MCDCMatrix",
    normal_matrix: "normalMatrix",
    light_color: "lightColor",
    light_direction: "lightDirectionVC",
    lights: 6,
    ambient_color: "ambientColorUniform",
    diffuse_color: "diffuseColorUniform",
    specular_color: "specularColorUniform",
    specular_power: "specularPowerUniform",
    opacity: "opacityUniform",
    intensities: ["ambientIntensity", "diffuseIntensity", "specularIntensity"],
    color_map: "colortexture",
    overrides_color: "OverridesColor",
    peeling: &["opaqueDepth", "lastDepthPeel", "translucentRGBATexture"],
};

// arbvis clip (single resolution): the clip value at p; the host keeps >= 0.5.
uniform sampler3D texture7;
float clip_value(vec3 p) { return texture(texture7, p).r; }

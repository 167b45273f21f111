/* placeholder */ typedef int glint_placeholder_mesh;

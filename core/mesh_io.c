/* placeholder */ typedef int glint_placeholder_mesh_io;

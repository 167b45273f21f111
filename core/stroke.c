/* placeholder */ typedef int glint_placeholder_stroke;

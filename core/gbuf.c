/* placeholder */ typedef int glint_placeholder_gbuf;

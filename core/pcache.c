/* placeholder */ typedef int glint_placeholder_pcache;

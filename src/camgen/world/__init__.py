"""The world's surfaces and light as pure functions: procedural textures (and, later, props, sky and
weather). `camgen.render` turns them into what it draws; nothing here touches OpenGL or files."""

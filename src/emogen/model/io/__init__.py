"""Reading and writing face models: ICT-FaceKit folders, glTF binaries, the compiled cache."""

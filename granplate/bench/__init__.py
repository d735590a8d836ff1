"""`granplate bench`: speed and accuracy of the schemes on the presets."""

"""Read a glTF binary back with pygltflib: accessors as arrays, joint nodes posed per frame."""

from dataclasses import dataclass

import numpy as np
import pygltflib
from scipy.spatial.transform import Rotation

_DTYPES = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}
_WIDTHS = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}


@dataclass
class GltfClip:
    document: pygltflib.GLTF2

    def accessor(self, index: int) -> np.ndarray:
        """Accessor ``index`` as ``(count,)`` or ``(count, width)``."""
        accessor = self.document.accessors[index]
        view = self.document.bufferViews[accessor.bufferView]
        width = _WIDTHS[accessor.type]
        values = np.frombuffer(self.document.binary_blob(), _DTYPES[accessor.componentType],
                               count=accessor.count * width,
                               offset=view.byteOffset + (accessor.byteOffset or 0))
        return values if width == 1 else values.reshape(accessor.count, width)

    @property
    def skin_joints(self) -> list[int]:
        return self.document.skins[0].joints

    def channels(self) -> dict[tuple[int, str], tuple[np.ndarray, np.ndarray]]:
        """``(node, path) -> (times, values)`` of the one animation."""
        animation = self.document.animations[0]
        out = {}
        for channel in animation.channels:
            sampler = animation.samplers[channel.sampler]
            out[channel.target.node, channel.target.path] = (self.accessor(sampler.input),
                                                             self.accessor(sampler.output))
        return out

    def local_transforms(self, node: int, n_frames: int) -> np.ndarray:
        """``(T, 4, 4)`` local matrices of ``node``: its channels, else its own TRS."""
        own = self.document.nodes[node]
        channels = self.channels()
        translation = channels.get((node, "translation"), (None, np.array(
            [own.translation or [0.0, 0.0, 0.0]])))[1]
        rotation = channels.get((node, "rotation"), (None, np.array(
            [own.rotation or [0.0, 0.0, 0.0, 1.0]])))[1]
        local = np.tile(np.eye(4), (n_frames, 1, 1))
        local[:, :3, :3] = Rotation.from_quat(np.broadcast_to(rotation, (n_frames, 4))).as_matrix()
        local[:, :3, 3] = np.broadcast_to(translation, (n_frames, 3))
        return local

    def joint_world_positions(self) -> np.ndarray:
        """``(T, J, 3)`` world positions of the skin's joints at every keyframe, metres."""
        nodes = self.document.nodes
        n_frames = len(next(iter(self.channels().values()))[0])
        world = {}
        pending = [(root, np.tile(np.eye(4), (n_frames, 1, 1)))
                   for root in self.document.scenes[0].nodes]
        while pending:
            node, parent_world = pending.pop()
            world[node] = parent_world @ self.local_transforms(node, n_frames)
            pending.extend((child, world[node]) for child in nodes[node].children or [])
        return np.stack([world[joint][:, :3, 3] for joint in self.skin_joints], axis=1)


def open_gltf(path) -> GltfClip:
    return GltfClip(pygltflib.GLTF2().load(str(path)))

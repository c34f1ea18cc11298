from setuptools import setup

package_name = 'rot_tools'

setup(
    name=package_name,
    version='0.1.0',
    packages=[package_name] + [package_name + '.' + sub for sub in ('core', 'io', 'cli', 'ros')],
    data_files=[
        ('share/ament_index/resource_index/packages',
            ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config',
            ['config/rot_tools.yaml', 'config/fastdds_profile.xml']),
        ('share/' + package_name + '/launch', ['launch/rot_tools.launch.xml']),
    ],
    install_requires=['setuptools', 'numpy', 'pyyaml'],
    extras_require={
        'test': ['pytest', 'hypothesis', 'scipy', 'matplotlib', 'rosbags==0.11.9',
                 'pyarrow==25.0.1', 'duckdb==2.0.0', 'dask==2026.8.0', 'distributed==2026.8.0'],
        'plot': ['matplotlib'],
        'bag': ['rosbags==0.11.9', 'pyarrow==25.0.1'],
        'fleet': ['dask==2026.8.0', 'distributed==2026.8.0'],
    },
    zip_safe=True,
    maintainer='rot_tools maintainers',
    maintainer_email='maintainers@rot-tools.example.org',
    description='Rotations, Euler angles, axis-angle and screw motions for ROS 2 and NumPy',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'rotation_node = rot_tools.ros.node.rotation_node:main',
            'rotation_client = rot_tools.ros.rotation_client:main',
            'rot-tools = rot_tools.cli.main:main',
        ],
    },
)
